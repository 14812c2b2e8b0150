#version 460
// The random-walk method per pixel: the GLSL twin of engine::random_walk_method::render
// (engine/src/random_walk_method.rs; read the two side by side). Pixels whose object has a
// translucent material get the mean of `spp` volumetric walks (sss/glsl/random_walk.glsl) on the
// object's own mesh, Fresnel-free diffuse boundary, next-event estimation at the exit; Lambert
// pixels get the path tracer's mean of `spp` samples, as method_pt.glsl computes it.
//
// Streams: the walks of a pixel share StreamKey { pixel, frame, 0, PURPOSE_WALK } and the light
// selection at their exits StreamKey { pixel, frame, 0, PURPOSE_WALK_LIGHT }, as on the CPU;
// path-traced sample s has its own stream (pt_sample_stream). Finite walk estimates are summed
// in f64 in sample order and divided by their count; path-traced ones are divided by spp.
//
// One dispatch per sample: dispatch `sample` (push constant pad[0]) runs walk or path-traced
// sample number `sample` of every pixel, carrying the two walk streams, the f64 sum and the
// tallies from the previous dispatch in RandomWalkPixelState (binding 13); the last one
// (sample = spp - 1) writes the mean. Lavapipe (llvmpipe) shares one budget of 65 535 loop
// iterations among all loops of an invocation group and silently cuts every loop short once
// it is spent (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS); one walk per dispatch keeps within it,
// and a probe loop at the end of each dispatch counts the dispatches where it was not
// (RandomWalkStats::cut), so a cut walk is never passed off as a result.
//
// Bindings: scene 0-8, 9 G-buffer (GPixel), 10 vec4 out (rgb = mean; w = samples left out as
// non-finite), 11 RandomWalkMedium per material (this method's own: the walk's sigma_s,
// sigma_t, g and interface, which GpuMaterial lacks), 12 RandomWalkStats per pixel (how its
// walks ended), 13 RandomWalkPixelState per pixel (carried between dispatches).
// Push constants: MethodParams (spp, then the sample index in pad[0]).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

// MethodParams (engine/src/contract.rs): spp; pad[0] is the sample this dispatch runs.
#include "contract/method_params.glsl"

#define SCENE_BINDING 0
#include "scene.glsl"
#include "pt.glsl"
#include "random_walk.glsl"
#include "loop_budget.glsl"

// The offset of SceneLighting::radiance's visibility ray at both ends.
const float SCENE_LIGHTING_EPSILON = 1e-4;

// How the walks of one pixel ended (std430, 36 bytes; Rust twin engine::vulkan::WalkStats):
// the sum of the exit weights (walk::Exit::weight) of exited walks, the largest |weight_c - 1|
// among them, the count of each WalkEnd, the non-finite samples (walks or path-traced) and the
// dispatches whose loops the device cut short.
struct RandomWalkStats {
    float weight_sum[3];
    float max_weight_deviation;
    uint exited;
    uint terminated;
    uint truncated;
    uint nonfinite;
    uint cut;
};

// What a pixel carries from one dispatch to the next (std430, 64 bytes; Rust twin
// engine::vulkan::WalkPixelState): the walk and light-selection streams, the f64 sum of
// the finite samples and their count.
struct RandomWalkPixelState {
    Stream walk;
    Stream selection;
    double sum[3];
    uint finite;
    uint pad;
};

layout(std430, binding = 9) readonly buffer GBufferIn { GPixel gbuffer[]; };
layout(std430, binding = 10) writeonly buffer ImageOut { vec4 image[]; };
layout(std430, binding = 11) readonly buffer Media { RandomWalkMedium media[]; };
layout(std430, binding = 12) buffer StatsInOut { RandomWalkStats stats[]; };
layout(std430, binding = 13) buffer StateInOut { RandomWalkPixelState states[]; };

// SceneLighting::selection: the light-selection stream of this invocation's pixel.
Stream scene_lighting_selection;

// intersect_light: the nearest t > 0 where origin + t dir meets the area light's surface (either
// side); false for delta lights and misses.
bool random_walk_method_intersect_light(uint light, vec3 origin, vec3 dir, out float t_hit,
                                        out vec3 point) {
    t_hit = 0.0;
    point = vec3(0.0);
    uint kind = scene_lights[light].kind;
    if (kind == LIGHT_QUAD || kind == LIGHT_TRIANGLE) {
        // Moller-Trumbore on the edges e1, e2; the triangle keeps u + v <= 1.
        bool triangle = kind == LIGHT_TRIANGLE;
        vec3 corner = light_p0(light);
        precise vec3 e1 = triangle ? light_p1(light) - corner : light_p1(light);
        precise vec3 e2 = triangle ? light_p2(light) - corner : light_p2(light);
        vec3 p = glam_cross(dir, e2);
        precise float det = glam_dot(e1, p);
        if (abs(det) < 1e-12) {
            return false;
        }
        precise vec3 s = origin - corner;
        precise float u = glam_dot(s, p) / det;
        vec3 q = glam_cross(s, e1);
        precise float v = glam_dot(dir, q) / det;
        precise float t = glam_dot(e2, q) / det;
        bool inside = u >= 0.0 && v >= 0.0 && (triangle ? u + v <= 1.0 : u <= 1.0 && v <= 1.0);
        if (!(inside && t > 0.0)) {
            return false;
        }
        t_hit = t;
        precise vec3 hit = origin + t * dir;
        point = hit;
        return true;
    }
    if (kind == LIGHT_SPHERE) {
        precise vec3 oc = origin - light_p0(light);
        float radius = scene_lights[light].radius;
        precise float b = glam_dot(oc, dir);
        precise float c = glam_length_squared(oc) - radius * radius;
        precise float disc = b * b - c;
        if (disc < 0.0) {
            return false;
        }
        precise float root = sqrt(disc);
        precise float near = -b - root;
        precise float far = -b + root;
        if (!(near > 0.0 || far > 0.0)) {
            return false;
        }
        precise float t = near > 0.0 ? near : far;
        t_hit = t;
        precise vec3 hit = origin + t * dir;
        point = hit;
        return true;
    }
    return false;
}

// SceneLighting::sample: a light point from the selection stream and u, with visibility.
bool exit_lighting_sample(vec3 point, vec3 normal, vec2 u, out ExitLightSample s) {
    s = ExitLightSample(vec3(0.0), vec3(0.0), 0.0, false);
    float pick = stream_next_f32(scene_lighting_selection);
    LightSample light;
    if (!lights_sample(point, vec3(pick, u.x, u.y), light)) {
        return false;
    }
    if (glam_dot(light.wi, normal) <= 0.0 || isnan(light.pdf) || light.pdf <= 0.0
        || pt_occluded(point, normal, light.wi, light.distance)) {
        return false;
    }
    precise vec3 radiance_over_pdf = light.radiance / light.pdf;
    s = ExitLightSample(light.wi, radiance_over_pdf, light.is_delta ? 0.0 : light.pdf,
                        light.is_delta);
    return true;
}

// SceneLighting::pdf: the sum over the area lights the ray crosses of selection x solid-angle
// density, in light order.
float exit_lighting_pdf(vec3 point, vec3 normal, vec3 wi) {
    precise float total = 0.0;
    for (uint l = 0u; l < LIGHT_COUNT; l++) {
        float t;
        vec3 hit;
        if (random_walk_method_intersect_light(l, point, wi, t, hit)) {
            total += lights_pdf(point, l, hit);
        }
    }
    return total;
}

// SceneLighting::radiance: L_e of the nearest light along wi (the first of equally near ones),
// zero when geometry blocks it.
vec3 exit_lighting_radiance(vec3 point, vec3 wi) {
    uint nearest = 0xFFFFFFFFu;
    float nearest_t = 0.0;
    vec3 nearest_point = vec3(0.0);
    for (uint l = 0u; l < LIGHT_COUNT; l++) {
        float t;
        vec3 hit;
        if (random_walk_method_intersect_light(l, point, wi, t, hit)
            && (nearest == 0xFFFFFFFFu || t < nearest_t)) {
            nearest = l;
            nearest_t = t;
            nearest_point = hit;
        }
    }
    if (nearest == 0xFFFFFFFFu) {
        return vec3(0.0);
    }
    precise float t_max = nearest_t - SCENE_LIGHTING_EPSILON;
    BvhRay ray;
    if (bvh_prepare(point, wi, SCENE_LIGHTING_EPSILON, t_max, ray)
        && bvh_traverse(ray, BVH_OCCLUDED, BVH_NO_HIT).prim != BVH_NO_HIT) {
        return vec3(0.0);
    }
    return lights_radiance(nearest, nearest_point, point);
}

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    if (pixel >= frame_params.width * frame_params.height) {
        return;
    }
    uint sample_index = params.pad[0];
    bool last = sample_index + 1u >= params.spp;
    RandomWalkStats tally = stats[pixel];
    RandomWalkPixelState state = states[pixel];
    if (sample_index == 0u) {
        tally = RandomWalkStats(float[3](0.0, 0.0, 0.0), 0.0, 0u, 0u, 0u, 0u, 0u);
        state.sum = double[3](0.0, 0.0, 0.0);
        state.finite = 0u;
    }
    GPixel x1 = gbuffer[pixel];
    if (x1.valid == 0u || params.spp == 0u) {
        image[pixel] = vec4(0.0);
        stats[pixel] = tally;
        states[pixel] = state;
        return;
    }
    precise dvec3 sum = dvec3(state.sum[0], state.sum[1], state.sum[2]);
    uint material = scene_material_of_object(x1.object);
    // As on the CPU, a material has a medium exactly when it is translucent.
    bool walk = material_is_translucent(scene_materials[material]);
    vec3 value;
    if (!walk) {
        // pt_estimate's Lambert branch, called directly so that its translucent branch is not
        // compiled in.
        Stream rng = pt_sample_stream(pixel, frame_params.frame, sample_index, scene_seed());
        value = pt_estimate_lambert(material_albedo(scene_materials[material]), x1, rng);
    } else {
        vec3 position = pt_vec3(x1.position);
        vec3 view = pt_vec3(x1.view);
        vec3 n = scene_geometric_normal(x1.prim);
        // The camera sees closed objects from outside: x1's outward normal faces the viewer.
        bool inward_winding = glam_dot(n, view) < 0.0;
        vec3 n1 = inward_winding ? -n : n;
        if (sample_index == 0u) {
            uint64_t seed = scene_seed();
            state.selection = stream_new(
                StreamKey(pixel, frame_params.frame, 0u, PURPOSE_WALK_LIGHT), seed);
            state.walk = stream_new(
                StreamKey(pixel, frame_params.frame, 0u, PURPOSE_WALK), seed);
        }
        scene_lighting_selection = state.selection;
        Stream stream = state.walk;
        RandomWalkExit exit;
        uint end = random_walk_estimate_exitant(x1.object, inward_winding, media[material],
                                                position, n1, view, true, stream, value, exit);
        state.walk = stream;
        state.selection = scene_lighting_selection;
        if (end == RANDOM_WALK_END_EXITED) {
            tally.exited++;
            precise vec3 weight_sum =
                vec3(tally.weight_sum[0], tally.weight_sum[1], tally.weight_sum[2]) + exit.weight;
            tally.weight_sum = float[3](weight_sum.x, weight_sum.y, weight_sum.z);
            vec3 deviation = abs(exit.weight - vec3(1.0));
            tally.max_weight_deviation =
                rust_max(tally.max_weight_deviation, random_walk_max_element(deviation));
        } else if (end == RANDOM_WALK_END_TERMINATED) {
            tally.terminated++;
        } else {
            tally.truncated++;
        }
    }
    if (any(isnan(value)) || any(isinf(value))) {
        tally.nonfinite++;
    } else {
        sum = sum + dvec3(value);
        state.finite++;
    }
    if (!loop_budget_intact(min(params.spp, 1u))) {
        tally.cut++;
    }
    state.sum = double[3](sum.x, sum.y, sum.z);
    if (last) {
        // pt::render divides by spp, random_walk_method::render by the finite walks.
        uint count = walk ? state.finite : params.spp;
        precise dvec3 mean = count > 0u ? sum / double(count) : dvec3(0.0);
        image[pixel] = vec4(vec3(mean), float(tally.nonfinite));
    }
    stats[pixel] = tally;
    states[pixel] = state;
}
