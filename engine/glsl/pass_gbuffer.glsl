#version 460
// G-buffer pass: the twin of sss::scene::GBuffer::render per pixel (sss/src/scene/gbuffer.rs):
// the closest hit of the frame's camera ray, normals flipped toward the camera.
// Bindings: the scene's, then PassKernel::GBuffer's (engine/src/plan/kernels.rs). One invocation
// per pixel.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

#include "contract/pass_params.glsl"

#define SCENE_BINDING 0
#include "scene.glsl"

#include "contract/pass_gbuffer_bindings.glsl"

// primary_hit: the G-buffer entry of pixel (px, py); valid = 0 on a miss.
GPixel primary_hit(uint px, uint py) {
    GPixel g;
    g.position = float[3](0.0, 0.0, 0.0);
    g.object = 0u;
    g.geometric_normal = float[3](0.0, 0.0, 0.0);
    g.prim = 0u;
    g.shading_normal = float[3](0.0, 0.0, 0.0);
    g.depth = 0.0;
    g.view = float[3](0.0, 0.0, 0.0);
    g.valid = 0u;
    vec3 origin;
    vec3 dir;
    camera_ray(frame_params.camera, px, py, origin, dir);
    BvhRay ray;
    if (!bvh_prepare(origin, dir, 0.0, burley_infinity(), ray)) {
        return g;
    }
    BvhHit hit = bvh_traverse(ray, BVH_CLOSEST, BVH_NO_HIT);
    if (hit.prim == BVH_NO_HIT) {
        return g;
    }
    // Ray::new stores dir + 0 (no −0 components); the view is its negation.
    vec3 stored_dir = vec3(dir.x == 0.0 ? 0.0 : dir.x, dir.y == 0.0 ? 0.0 : dir.y,
        dir.z == 0.0 ? 0.0 : dir.z);
    vec3 view = -stored_dir;
    vec3 n = scene_geometric_normal(hit.prim);
    float side = glam_dot(n, view) < 0.0 ? -1.0 : 1.0;
    precise vec3 geometric = side * n;
    precise vec3 shading = side * scene_shading_normal(hit.prim, hit.bary);
    vec3 position = scene_position(hit.prim, hit.bary);
    g.position = float[3](position.x, position.y, position.z);
    g.object = hit.object;
    g.geometric_normal = float[3](geometric.x, geometric.y, geometric.z);
    g.prim = hit.prim;
    g.shading_normal = float[3](shading.x, shading.y, shading.z);
    g.depth = hit.t;
    g.view = float[3](view.x, view.y, view.z);
    g.valid = 1u;
    return g;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= frame_params.width * frame_params.height) {
        return;
    }
    gpixels[i] = primary_hit(i % frame_params.width, i / frame_params.width);
}
