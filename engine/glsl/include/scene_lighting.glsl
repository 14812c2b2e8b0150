// The scene's lights at the exits of a path leaving a translucent object: the GLSL twin of
// engine::scene_lighting::{SceneLighting, intersect_light} (engine/src/scene_lighting.rs;
// read the two side by side). Defines the three exit_lighting_* functions that
// sss/glsl/random_walk.glsl declares: light samples with shadow rays, the pdf and the radiance
// of the nearest area light along a direction with its visibility ray.
//
// The including kernel includes scene.glsl, pt.glsl and random_walk.glsl first, then this file,
// and sets scene_lighting_selection to its pixel's light-selection stream before each path (and
// stores it back after, when the stream is carried between dispatches): SceneLighting::sample
// draws the light pick from it, the path supplies the other two numbers. Used by
// method_random_walk.glsl and methods/src/single_scatter/method_single_scatter.glsl (through the
// include path the engine publishes, engine/build.rs).

#ifndef ENGINE_SCENE_LIGHTING_GLSL
#define ENGINE_SCENE_LIGHTING_GLSL

// The offset of SceneLighting::radiance's visibility ray at both ends.
const float SCENE_LIGHTING_EPSILON = 1e-4;

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

// SceneLighting::radiance: the sum, in light order, of L_e of every area light along wi that
// geometry does not block (lights are transparent, as for the shadow rays of exit_lighting_sample).
vec3 exit_lighting_radiance(vec3 point, vec3 wi) {
    precise vec3 total = vec3(0.0);
    for (uint l = 0u; l < LIGHT_COUNT; l++) {
        float t;
        vec3 hit;
        if (!random_walk_method_intersect_light(l, point, wi, t, hit)) {
            continue;
        }
        precise float t_max = t - SCENE_LIGHTING_EPSILON;
        BvhRay ray;
        if (bvh_prepare(point, wi, SCENE_LIGHTING_EPSILON, t_max, ray)
            && bvh_traverse(ray, BVH_OCCLUDED, BVH_NO_HIT).prim != BVH_NO_HIT) {
            continue;
        }
        total += lights_radiance(l, hit, point);
    }
    return total;
}

#endif
