// The scene on the device (engine::vulkan::GpuScene): bindings SCENE_BINDING + 0 .. + 8 of
// the Vulkan backend contract, the per-pixel GPixel and the per-frame FrameParams, and twins of
// geometry::Geometry's triangle accessors (geometry/src/bvh.rs).
//
// The including shader enables GL_EXT_shader_explicit_arithmetic_types_int64 and defines
// SCENE_BINDING (0 in every pass shader) before including this file.
//   + 0 .. + 3  the BVH (bvh.glsl)
//   + 4  scene_triangles: GpuTriangle per global triangle id (vertices, shading normals)
//   + 5  scene_objects: material index per object id
//   + 6  scene_materials: GpuMaterial (material.glsl)
//   + 7  scene_lights: GpuLight (light.glsl)
//   + 8  frame_params: FrameParams

#ifndef SSS_SCENE_GLSL
#define SSS_SCENE_GLSL

#include "frame.glsl"
#include "camera.glsl"
#include "material.glsl"

// GpuTriangle, FrameParams and GPixel (engine/src/contract.rs).
#include "contract/engine.glsl"

layout(std430, binding = SCENE_BINDING + 4) readonly buffer SceneTriangles { GpuTriangle scene_triangles[]; };
layout(std430, binding = SCENE_BINDING + 5) readonly buffer SceneObjects { uint scene_objects[]; };
layout(std430, binding = SCENE_BINDING + 6) readonly buffer SceneMaterials { GpuMaterial scene_materials[]; };
layout(std430, binding = SCENE_BINDING + 8) readonly buffer SceneFrame { FrameParams frame_params; };

#define LIGHT_COUNT frame_params.light_count
#include "light.glsl"

#define BVH_BINDING SCENE_BINDING
#define BVH_NODE_COUNT frame_params.node_count
#include "bvh.glsl"

uint scene_seed_lo() {
    return frame_params.seed_lo;
}

uint scene_seed_hi() {
    return frame_params.seed_hi;
}

// The run seed as restir::rng takes it.
uint64_t scene_seed() {
    return uint64_t(frame_params.seed_lo) | (uint64_t(frame_params.seed_hi) << 32);
}

// Geometry::vertices.
void scene_vertices(uint prim, out vec3 v0, out vec3 v1, out vec3 v2) {
    GpuTriangle t = scene_triangles[prim];
    v0 = vec3(t.v[0], t.v[1], t.v[2]);
    v1 = vec3(t.v[3], t.v[4], t.v[5]);
    v2 = vec3(t.v[6], t.v[7], t.v[8]);
}

// Geometry::position: v0 + u (v1 − v0) + v (v2 − v0).
vec3 scene_position(uint prim, vec2 bary) {
    vec3 v0;
    vec3 v1;
    vec3 v2;
    scene_vertices(prim, v0, v1, v2);
    precise vec3 p = v0 + bary.x * (v1 - v0) + bary.y * (v2 - v0);
    return p;
}

// Geometry::geometric_normal: unit (v1 − v0) × (v2 − v0), zero for a degenerate triangle.
vec3 scene_geometric_normal(uint prim) {
    vec3 v0;
    vec3 v1;
    vec3 v2;
    scene_vertices(prim, v0, v1, v2);
    precise vec3 e1 = v1 - v0;
    precise vec3 e2 = v2 - v0;
    return glam_normalize_or_zero(glam_cross(e1, e2));
}

// Geometry::shading_normal: the interpolated vertex normal, renormalised; the geometric normal
// where it vanishes.
vec3 scene_shading_normal(uint prim, vec2 bary) {
    GpuTriangle t = scene_triangles[prim];
    vec3 n0 = vec3(t.n[0], t.n[1], t.n[2]);
    vec3 n1 = vec3(t.n[3], t.n[4], t.n[5]);
    vec3 n2 = vec3(t.n[6], t.n[7], t.n[8]);
    precise float w0 = 1.0 - bary.x - bary.y;
    precise vec3 n = w0 * n0 + bary.x * n1 + bary.y * n2;
    vec3 unit;
    return glam_try_normalize(n, unit) ? unit : scene_geometric_normal(prim);
}

// Geometry::triangle_area: ½ ‖(v1 − v0) × (v2 − v0)‖.
float scene_triangle_area(uint prim) {
    vec3 v0;
    vec3 v1;
    vec3 v2;
    scene_vertices(prim, v0, v1, v2);
    precise vec3 e1 = v1 - v0;
    precise vec3 e2 = v2 - v0;
    precise float area = 0.5 * glam_length(glam_cross(e1, e2));
    return area;
}

// Geometry::object_of.
uint scene_object_of(uint prim) {
    return scene_triangles[prim].object;
}

// Scene::objects[object].material: the index into scene_materials.
uint scene_material_of_object(uint object) {
    return scene_objects[object];
}

// Scene::material_of_object.
GpuMaterial scene_material(uint object) {
    return scene_materials[scene_objects[object]];
}

#endif
