#version 460
// The image-space method per pixel: the GLSL twin of methods/src/image_space/cpu.rs render (read
// the two side by side; the math is image_space.glsl beside it). Each pass `pass` is two
// dispatches over the frame's G-buffer:
//   stage IMAGE_SPACE_STAGE_IRRADIANCE: E(x_q) of every translucent pixel into binding 11
//     (image_space_irradiance_at, stream { q, frame, pass, IMAGE_SPACE_PURPOSE_IRRADIANCE });
//   stage IMAGE_SPACE_STAGE_GATHER: per translucent pixel the gather over the tangent plane
//     (image_space_gather_pixel, stream { o, frame, pass, IMAGE_SPACE_PURPOSE_GATHER }) and
//     image_space_exit_radiance; per Lambert pixel the path tracer's sample `pass`.
// The gather reads the irradiance of other pixels, so the host dispatches the two stages in
// turn (each dispatch completes before the next). A finite pass value is added to the pixel's
// f64 sum in pass order, a non-finite one (or a path-traced sample whose probe had more than
// BVH_MAX_HITS hits) is left out of the sum but not of the divisor, as on the CPU; the last
// gather (pass = spp - 1) writes the mean (sum / spp in f64, rounded to f32).
//
// Bindings: scene 0-8, 9 G-buffer (GPixel), 10 vec4 out (rgb = mean, w = pass values left out),
// 11 vec4 irradiance per pixel (this pass's E in rgb), 12 GatherProfile per material (computed on
// the host as GatherProfile::new does; a zeroed placeholder for Lambert materials),
// 13 ImageSpaceState per pixel (the running sum, tallies and EntryCounts between dispatches).
// Push constants: ImageSpaceParams.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

#include "contract/image_space_params.glsl"

#define SCENE_BINDING 0
#include "contract/engine.glsl"
#include "contract/image_space.glsl"
#define BVH_MAX_HITS KEPT_HITS
#include "scene.glsl"
#include "image_space.glsl"
#include "loop_budget.glsl"

layout(std430, binding = 9) readonly buffer GBufferIn { GPixel gbuffer[]; };
layout(std430, binding = 10) writeonly buffer ImageOut { vec4 image[]; };
layout(std430, binding = 11) buffer Irradiance { vec4 irradiance[]; };
layout(std430, binding = 12) readonly buffer Profiles { GatherProfile profiles[]; };
layout(std430, binding = 13) buffer StateBuffer { ImageSpaceState state[]; };

GPixel image_space_fetch_pixel(uint pixel) {
    return gbuffer[pixel];
}

vec3 image_space_fetch_irradiance(uint pixel) {
    return irradiance[pixel].xyz;
}

// image_space::irradiance for one pixel: E on translucent pixels, 0 elsewhere.
void irradiance_stage(uint pixel, GPixel g) {
    vec3 e = vec3(0.0);
    if (g.valid != 0u) {
        GpuMaterial material = scene_material(g.object);
        if (material_is_translucent(material)) {
            Stream rng = image_space_irradiance_stream(pixel, frame_params.frame, params.pass,
                scene_seed());
            e = image_space_irradiance_at(g, material_fresnel(material),
                params.irradiance_samples, rng);
        }
    }
    irradiance[pixel] = vec4(e, 0.0);
}

// One pass value of pass_values and its addition to the running sum of render.
void gather_stage(uint pixel, GPixel g, inout ImageSpaceState carried) {
    if (g.valid == 0u) {
        return;
    }
    uint overflow = pt_hit_overflow;
    vec3 value;
    GpuMaterial material = scene_material(g.object);
    if (material_is_translucent(material)) {
        GatherProfile profile = profiles[scene_material_of_object(g.object)];
        Receiver receiver;
        receiver.position = pt_vec3(g.position);
        receiver.frame = frame_from_normal(pt_vec3(g.geometric_normal));
        receiver.eye = camera_eye(frame_params.camera);
        ImageSpaceSettings settings = ImageSpaceSettings(params.irradiance_samples,
            params.importance_samples, params.uniform_samples, float[3](0.0, 0.0, 0.0));
        EntryCounts counts = EntryCounts(carried.samples, carried.off_screen, carried.occluded,
            carried.outside, carried.edge_on);
        Stream rng = image_space_gather_stream(pixel, frame_params.frame, params.pass,
            scene_seed());
        vec3 b = image_space_gather_pixel(receiver, profile, settings, frame_params.camera,
            g.object, rng, counts);
        carried.samples = counts.samples;
        carried.off_screen = counts.off_screen;
        carried.occluded = counts.occluded;
        carried.outside = counts.outside;
        carried.edge_on = counts.edge_on;
        value = image_space_exit_radiance(g, profile.fresnel, b);
    } else {
        Stream rng = pt_sample_stream(pixel, frame_params.frame, params.pass, scene_seed());
        value = pt_estimate(g, PT_HITS_ALL, rng);
    }
    pt_accumulate(value, overflow, carried.sum, carried.left_out);
}

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    if (pixel >= frame_params.width * frame_params.height) {
        return;
    }
    GPixel g = gbuffer[pixel];
    ImageSpaceState carried = state[pixel];
    if (params.pass == 0u && params.stage == IMAGE_SPACE_STAGE_IRRADIANCE) {
        carried = ImageSpaceState(double[3](0.0, 0.0, 0.0), 0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u);
    }
    if (params.stage == IMAGE_SPACE_STAGE_IRRADIANCE) {
        irradiance_stage(pixel, g);
    } else {
        gather_stage(pixel, g, carried);
    }
    if (!loop_budget_intact(min(frame_params.width, 1u))) {
        carried.cut++;
    }
    state[pixel] = carried;
    if (params.stage == IMAGE_SPACE_STAGE_GATHER && params.pass + 1u == params.spp) {
        precise dvec3 mean = dvec3(carried.sum[0], carried.sum[1], carried.sum[2])
            / double(params.spp);
        image[pixel] = vec4(vec3(mean), float(carried.left_out));
    }
}
