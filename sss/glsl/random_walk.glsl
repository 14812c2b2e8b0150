// Volumetric random walk in a homogeneous medium: the GLSL twin of sss/src/random_walk/
// (phase.rs, interface.rs — its fresnel_dielectric in fresnel.glsl —, boundary.rs MeshBoundary,
// walk.rs, estimate.rs; read them side by
// side: same stream draws in the same order, same operation order, `precise` locals).
//
// The including shader enables GL_EXT_shader_explicit_arithmetic_types_int64, includes rng.glsl
// and scene.glsl (the BVH and scene_geometric_normal) before this file, and defines the three
// exit_lighting_* functions declared below (the ExitLighting trait of lighting.rs).
//
// Bounds (no recursion, no allocation): a walk has at most RANDOM_WALK_DEFAULT_MAX_BOUNCES
// segments, as on the CPU (WalkSettings::default), and ends RANDOM_WALK_END_TRUNCATED there. The
// mesh boundary skips at most RANDOM_WALK_MAX_ENTRY_SKIPS entering hits per query (the CPU loop is
// unbounded); past that the walk also ends RANDOM_WALK_END_TRUNCATED, so the caller counts it with
// the cap.
// On lavapipe every loop iteration (the BVH traversal's included) also draws on a budget of
// 65 535 per invocation group; method_random_walk.glsl runs one walk per dispatch and detects
// a spent budget.
//
// Not bit-exact with the CPU: free flights use log, transmittance ratios exp, phase and cosine
// sampling sin/cos, each a few ulp off the CPU's libm. A walk follows the CPU's path (same
// stream, same decisions) until such an ulp flips a discrete decision (collision before or
// after the boundary, which triangle is hit, Russian roulette), after which it is an
// independent walk of the same estimator.

#ifndef SSS_RANDOM_WALK_GLSL
#define SSS_RANDOM_WALK_GLSL

#include "frame.glsl"
#include "fresnel.glsl"
// RANDOM_WALK_DEFAULT_MAX_BOUNCES, RANDOM_WALK_SMALL_G, the interfaces BOUNDARY_*, the crossings
// RANDOM_WALK_CROSSING_* and the ends RANDOM_WALK_END_* (sss/src/contract.rs).
#include "contract/sss.glsl"

const float RANDOM_WALK_TAU = 6.28318530717958647692;
const float RANDOM_WALK_FRAC_1_PI = 0.318309886183790671538;
// phase::ISOTROPIC = 0.25 * FRAC_1_PI, computed in f32 as on the CPU.
const float RANDOM_WALK_ISOTROPIC = 0.25 * RANDOM_WALK_FRAC_1_PI;
// Entering hits MeshBoundary::intersect may skip in one query before the walk is cut off: a
// bound of the GPU loop only (the CPU loop has none), so not part of the contract.
const uint RANDOM_WALK_MAX_ENTRY_SKIPS = 64u;

// The medium of one material (std430, 48 bytes; Rust twin engine::vulkan::GpuMedium):
// Medium::sigma_s() and Medium::sigma_t() as the host computes them, HG g, the interface and
// its eta.
struct RandomWalkMedium {
    float sigma_s[3];
    float sigma_t[3];
    float g;
    uint interface_kind;
    float eta;
    uint pad0;
    uint pad1;
    uint pad2;
};

// walk::Exit; `diffuse` selects ExitDirection::Diffuse, else Specular(`direction`).
struct RandomWalkExit {
    vec3 point;
    vec3 normal;
    bool diffuse;
    vec3 direction;
    vec3 weight;
    uint scatter_count;
    uint reflection_count;
};

// lighting::LightSample.
struct ExitLightSample {
    vec3 wi;
    vec3 radiance_over_pdf;
    float pdf;
    bool is_delta;
};

// lighting::ExitLighting, defined by the including shader.
bool exit_lighting_sample(vec3 point, vec3 normal, vec2 u, out ExitLightSample s);
float exit_lighting_pdf(vec3 point, vec3 normal, vec3 wi);
vec3 exit_lighting_radiance(vec3 point, vec3 wi);

// f32::signum: -1 for negative numbers and -0.0, +1 otherwise (GLSL sign(-0.0) is 0).
float random_walk_signum(float x) {
    return (floatBitsToUint(x) >> 31) != 0u ? -1.0 : 1.0;
}

// glam's Vec3::any_orthonormal_pair [Duff et al. 2017].
void random_walk_orthonormal_pair(vec3 v, out vec3 t, out vec3 b) {
    precise float sign = random_walk_signum(v.z);
    precise float a = -1.0 / (sign + v.z);
    precise float bb = v.x * v.y * a;
    precise vec3 tt = vec3(1.0 + sign * v.x * v.x * a, sign * bb, -sign * v.x);
    precise vec3 b2 = vec3(bb, sign + v.y * v.y * a, -v.y);
    t = tt;
    b = b2;
}

// glam's Vec3::max_element.
float random_walk_max_element(vec3 v) {
    float yz = v.y > v.z ? v.y : v.z;
    return v.x > yz ? v.x : yz;
}

// ---- phase.rs: Henyey-Greenstein ----

// HenyeyGreenstein::eval_cos: (1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^{3/2}).
float henyey_greenstein_eval_cos(float g, float cos_theta) {
    precise float denom = 1.0 + g * g - 2.0 * g * cos_theta;
    precise float p = RANDOM_WALK_ISOTROPIC * (1.0 - g * g) / (denom * sqrt(denom));
    return p;
}

// HenyeyGreenstein::pdf_cos.
float henyey_greenstein_pdf_cos(float g, float cos_theta) {
    return abs(g) < RANDOM_WALK_SMALL_G ? RANDOM_WALK_ISOTROPIC
                                        : henyey_greenstein_eval_cos(g, cos_theta);
}

// HenyeyGreenstein::sample_cos (inverse CDF), clamped to [-1, 1].
float henyey_greenstein_sample_cos(float g, float u) {
    precise float cos_theta;
    if (abs(g) < RANDOM_WALK_SMALL_G) {
        cos_theta = 1.0 - 2.0 * u;
    } else {
        precise float s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
        cos_theta = (1.0 + g * g - s * s) / (2.0 * g);
    }
    return rust_clamp(cos_theta, -1.0, 1.0);
}

// HenyeyGreenstein::invert_cos: the CDF of the sampled cos theta.
float henyey_greenstein_invert_cos(float g, float cos_theta) {
    if (abs(g) < RANDOM_WALK_SMALL_G) {
        precise float u = 0.5 * (1.0 - cos_theta);
        return u;
    }
    precise float root = sqrt(1.0 + g * g - 2.0 * g * cos_theta);
    precise float u = (1.0 - g * g) / (2.0 * g) * (1.0 / root - 1.0 / (1.0 + g));
    return rust_clamp(u, 0.0, 1.0);
}

// HenyeyGreenstein::sample (PhaseFunction): the scattered direction, its phase value and the
// density it was drawn with.
void henyey_greenstein_sample(float g, vec3 dir_in, vec2 u, out vec3 dir, out float value,
                              out float pdf) {
    precise float cos_theta = henyey_greenstein_sample_cos(g, u.x);
    precise float sin_theta = sqrt(rust_max(1.0 - cos_theta * cos_theta, 0.0));
    precise float phi = RANDOM_WALK_TAU * u.y;
    precise float sin_phi = sin(phi);
    precise float cos_phi = cos(phi);
    vec3 t;
    vec3 b;
    random_walk_orthonormal_pair(dir_in, t, b);
    precise vec3 d = (sin_theta * cos_phi) * t + (sin_theta * sin_phi) * b + cos_theta * dir_in;
    dir = glam_normalize(d);
    value = henyey_greenstein_eval_cos(g, cos_theta);
    pdf = henyey_greenstein_pdf_cos(g, cos_theta);
}

// HenyeyGreenstein::pdf (PhaseFunction).
float henyey_greenstein_pdf(float g, vec3 dir_in, vec3 dir_out) {
    return henyey_greenstein_pdf_cos(g, glam_dot(dir_in, dir_out));
}

// ---- interface.rs ----

// refract: false under total internal reflection; n faces the incident side.
bool random_walk_refract(vec3 dir, vec3 n, float eta, out vec3 result) {
    result = vec3(0.0);
    precise float cos_i = -glam_dot(dir, n);
    precise float sin2_t = rust_max(1.0 - cos_i * cos_i, 0.0) / (eta * eta);
    if (sin2_t >= 1.0) {
        return false;
    }
    precise float cos_t = sqrt(1.0 - sin2_t);
    precise vec3 v = dir / eta + (cos_i / eta - cos_t) * n;
    result = glam_normalize(v);
    return true;
}

// reflect: mirror reflection of the propagation direction about n.
vec3 random_walk_reflect(vec3 dir, vec3 n) {
    precise vec3 r = dir - (2.0 * glam_dot(dir, n)) * n;
    return r;
}

// sampling::sample_cosine_hemisphere: a cosine-distributed direction about `axis` (Malley); pdf random_walk_cosine_pdf.
vec3 random_walk_sample_cosine(vec3 axis, vec2 u) {
    precise float r = sqrt(u.x);
    precise float phi = RANDOM_WALK_TAU * u.y;
    precise float sin_phi = sin(phi);
    precise float cos_phi = cos(phi);
    precise float z = sqrt(rust_max(1.0 - u.x, 0.0));
    vec3 t;
    vec3 b;
    random_walk_orthonormal_pair(axis, t, b);
    precise vec3 d = (r * cos_phi) * t + (r * sin_phi) * b + z * axis;
    return glam_normalize(d);
}

// sampling::cosine_hemisphere_pdf: max(0, cos theta) / pi.
float random_walk_cosine_pdf(vec3 axis, vec3 dir) {
    precise float p = rust_max(glam_dot(axis, dir), 0.0) * RANDOM_WALK_FRAC_1_PI;
    return p;
}

// ---- boundary.rs: MeshBoundary ----

// MeshBoundary::intersect: the first hit on `object` in (0, t_max) where the ray leaves it
// (outward normal . dir > 0), entering hits skipped. Returns 1 with t and the outward normal,
// 0 when the boundary is not reached before t_max, 2 when more than
// RANDOM_WALK_MAX_ENTRY_SKIPS entering hits were skipped (the CPU would go on).
uint random_walk_mesh_intersect(uint object, bool inward_winding, vec3 origin, vec3 dir,
                                float t_max, out float t, out vec3 normal) {
    t = 0.0;
    normal = vec3(0.0);
    float t_min = 0.0;
    for (uint skip = 0u; skip <= RANDOM_WALK_MAX_ENTRY_SKIPS; skip++) {
        BvhRay ray;
        if (!bvh_prepare(origin, dir, t_min, t_max, ray)) {
            return 0u;
        }
        BvhHit hit = bvh_traverse(ray, BVH_CLOSEST, object);
        if (hit.prim == BVH_NO_HIT) {
            return 0u;
        }
        vec3 n = scene_geometric_normal(hit.prim);
        n = inward_winding ? -n : n;
        if (glam_dot(n, dir) > 0.0) {
            t = hit.t;
            normal = n;
            return 1u;
        }
        t_min = hit.t;
    }
    return 2u;
}

// ---- walk.rs ----

// cross: the boundary event of a path along `dir` meeting the boundary with outward `normal`.
// Index-matched and diffuse interfaces always leave; a dielectric (inside -> outside, relative
// index 1/eta) reflects with the Fresnel probability, drawing one number only when refraction is
// possible. Returns the Crossing; `direction` is the specular exit (the incoming direction for
// index-matched) or the reflected direction.
uint random_walk_cross(uint interface_kind, float eta, vec3 dir, vec3 normal, inout Stream stream,
                       out vec3 direction) {
    direction = dir;
    if (interface_kind == BOUNDARY_INDEX_MATCHED) {
        return RANDOM_WALK_CROSSING_LEAVES_SPECULAR;
    }
    if (interface_kind == BOUNDARY_DIFFUSE) {
        return RANDOM_WALK_CROSSING_LEAVES_DIFFUSE;
    }
    precise float inv_eta = 1.0 / eta;
    float fresnel = fresnel_dielectric(glam_dot(dir, normal), inv_eta);
    vec3 out_dir;
    if (random_walk_refract(dir, -normal, inv_eta, out_dir) && stream_next_f32(stream) >= fresnel) {
        direction = out_dir;
        return RANDOM_WALK_CROSSING_LEAVES_SPECULAR;
    }
    direction = random_walk_reflect(dir, normal);
    return RANDOM_WALK_CROSSING_REFLECTED;
}

// roulette: survival with q = min(1, max_c beta_c); false = killed.
bool random_walk_roulette(vec3 beta, float u, out vec3 survivor) {
    survivor = vec3(0.0);
    // f32::min returns the other operand for NaN: a NaN weight gives q = 1, as on the CPU.
    float q = rust_min(random_walk_max_element(beta), 1.0);
    if (u >= q) {
        return false;
    }
    precise vec3 s = beta / q;
    survivor = s;
    return true;
}

// transmittance_ratio: e^{-(sigma_t,c - sigma_t,h) t} per channel.
vec3 random_walk_transmittance_ratio(vec3 sigma_t, float sigma_hero, float t) {
    precise vec3 x = -(sigma_t - vec3(sigma_hero)) * t;
    return exp(x);
}

// rescale: (beta, r) / mean(r).
void random_walk_rescale(inout vec3 beta, inout vec3 r) {
    precise float mean = (r.x + r.y + r.z) / 3.0;
    precise vec3 b = beta / mean;
    precise vec3 rr = r / mean;
    beta = b;
    r = rr;
}

// walk: from `start` along `dir` (into the medium) until it exits, is terminated or truncated.
// Returns the WalkEnd; `exit` is filled when RANDOM_WALK_END_EXITED. The loop has a single exit
// (`break`), no `return` inside it.
uint random_walk_walk(uint object, bool inward_winding, RandomWalkMedium medium, vec3 start,
                      vec3 dir_in, bool roulette, inout Stream stream, out RandomWalkExit exit) {
    exit = RandomWalkExit(vec3(0.0), vec3(0.0), false, vec3(0.0), vec3(0.0), 0u, 0u);
    vec3 sigma_t = vec3(medium.sigma_t[0], medium.sigma_t[1], medium.sigma_t[2]);
    vec3 sigma_s = vec3(medium.sigma_s[0], medium.sigma_s[1], medium.sigma_s[2]);
    uint hero = min(uint(3.0 * stream_next_f32(stream)), 2u);
    float sigma_hero = sigma_t[hero];
    precise vec3 beta = vec3(1.0);
    precise vec3 r = vec3(1.0);
    precise vec3 pos = start;
    vec3 dir = dir_in;
    uint scatter_count = 0u;
    uint reflection_count = 0u;
    uint end = RANDOM_WALK_END_TRUNCATED;
    for (uint bounce = 0u; bounce < RANDOM_WALK_DEFAULT_MAX_BOUNCES; bounce++) {
        // Free flight with pdf sigma_t,h e^{-sigma_t,h t} [000 slide 54].
        precise float t_collision = -log(1.0 - stream_next_f32(stream)) / sigma_hero;
        float t_hit;
        vec3 normal;
        uint found = random_walk_mesh_intersect(object, inward_winding, pos, dir, t_collision,
                                                t_hit, normal);
        if (found == 2u) {
            break;
        }
        if (found == 1u) {
            // Boundary first: f_c = p_c = e^{-sigma_t,c d} [000 slide 66].
            vec3 ratio = random_walk_transmittance_ratio(sigma_t, sigma_hero, t_hit);
            beta = beta * ratio;
            r = r * ratio;
            random_walk_rescale(beta, r);
            pos += t_hit * dir;
            vec3 out_dir;
            uint crossing =
                random_walk_cross(medium.interface_kind, medium.eta, dir, normal, stream, out_dir);
            if (crossing != RANDOM_WALK_CROSSING_REFLECTED) {
                bool diffuse = crossing == RANDOM_WALK_CROSSING_LEAVES_DIFFUSE;
                exit = RandomWalkExit(pos, normal, diffuse, out_dir, beta, scatter_count,
                                      reflection_count);
                end = RANDOM_WALK_END_EXITED;
                break;
            }
            dir = out_dir;
            reflection_count += 1u;
        } else {
            // Collision: f_c = sigma_s,c e^{-sigma_t,c t}, p_c = sigma_t,c e^{-sigma_t,c t}
            // [000 slide 66].
            pos += t_collision * dir;
            precise vec3 ratio =
                random_walk_transmittance_ratio(sigma_t, sigma_hero, t_collision) / sigma_hero;
            beta = beta * sigma_s * ratio;
            r = r * sigma_t * ratio;
            random_walk_rescale(beta, r);
            scatter_count += 1u;
            vec2 u;
            u.x = stream_next_f32(stream);
            u.y = stream_next_f32(stream);
            vec3 scattered;
            float value;
            float pdf;
            henyey_greenstein_sample(medium.g, dir, u, scattered, value, pdf);
            if (isnan(pdf) || pdf <= 0.0) {
                end = RANDOM_WALK_END_TERMINATED;
                break;
            }
            beta *= value / pdf;
            dir = scattered;
            vec3 survivor;
            bool alive;
            if (roulette) {
                alive = random_walk_roulette(beta, stream_next_f32(stream), survivor);
            } else {
                survivor = beta;
                alive = random_walk_max_element(beta) > 0.0;
            }
            if (!alive) {
                end = RANDOM_WALK_END_TERMINATED;
                break;
            }
            beta = survivor;
        }
    }
    return end;
}

// ---- estimate.rs ----

// incident: radiance arriving from outside through the boundary point (outward `normal`) as
// transmitted into a path leaving there: NEE + one escape direction under the balance heuristic
// at a diffuse exit, the lighting's radiance along a specular one (`direction`).
vec3 random_walk_incident(vec3 point, vec3 normal, bool diffuse, vec3 direction,
                          inout Stream stream) {
    if (!diffuse) {
        return exit_lighting_radiance(point, direction);
    }
    precise vec3 total = vec3(0.0);
    // Next-event estimation: f = 1/pi, weight f cos / p_light, balance heuristic.
    vec2 u;
    u.x = stream_next_f32(stream);
    u.y = stream_next_f32(stream);
    ExitLightSample light;
    if (exit_lighting_sample(point, normal, u, light)) {
        precise float p_escape = random_walk_cosine_pdf(normal, light.wi);
        if (p_escape > 0.0) {
            precise float mis = light.is_delta ? 1.0 : light.pdf / (light.pdf + p_escape);
            total += (mis * p_escape) * light.radiance_over_pdf;
        }
    }
    // Escape direction, cosine-sampled: f cos / p = 1.
    u.x = stream_next_f32(stream);
    u.y = stream_next_f32(stream);
    vec3 out_dir = random_walk_sample_cosine(normal, u);
    precise float p_escape = random_walk_cosine_pdf(normal, out_dir);
    if (p_escape > 0.0) {
        precise float p_light = exit_lighting_pdf(point, normal, out_dir);
        total += (p_escape / (p_escape + p_light)) * exit_lighting_radiance(point, out_dir);
    }
    return total;
}

// enter: the inward direction and weight of a path entering at a boundary point (outward n1)
// against wo; false when wo is below the surface or cannot refract. Draws two numbers for the
// diffuse interface, none otherwise.
bool random_walk_enter(uint interface_kind, float eta, vec3 n1, vec3 wo, inout Stream stream,
                       out vec3 dir, out float weight) {
    dir = vec3(0.0);
    weight = 1.0;
    float cos_o = glam_dot(wo, n1);
    if (cos_o <= 0.0) {
        return false;
    }
    if (interface_kind == BOUNDARY_INDEX_MATCHED) {
        dir = -wo;
        return true;
    }
    if (interface_kind == BOUNDARY_DIELECTRIC) {
        // Refraction of the camera ray into the medium, weighted by the transmittance 1 - F.
        if (!random_walk_refract(-wo, n1, eta, dir)) {
            return false;
        }
        weight = 1.0 - fresnel_dielectric(cos_o, eta);
        return true;
    }
    // Lambertian transmission: cosine-sampled inward direction, f cos / pdf = 1.
    vec2 u;
    u.x = stream_next_f32(stream);
    u.y = stream_next_f32(stream);
    dir = random_walk_sample_cosine(-n1, u);
    return true;
}

// estimate_exitant_with: one sample of the subsurface radiance leaving x1 (outward normal n1)
// toward wo, carried by a walk on the mesh `object`. Returns the WalkEnd
// (RANDOM_WALK_END_TERMINATED, without drawing, when wo is below the surface); `exit` reports the
// walk's exit.
uint random_walk_estimate_exitant(uint object, bool inward_winding, RandomWalkMedium medium,
                                  vec3 x1, vec3 n1, vec3 wo, bool roulette, inout Stream stream,
                                  out vec3 radiance, out RandomWalkExit exit) {
    radiance = vec3(0.0);
    exit = RandomWalkExit(vec3(0.0), vec3(0.0), false, vec3(0.0), vec3(0.0), 0u, 0u);
    vec3 dir;
    float entry_weight;
    if (!random_walk_enter(medium.interface_kind, medium.eta, n1, wo, stream, dir, entry_weight)) {
        return RANDOM_WALK_END_TERMINATED;
    }
    uint end = random_walk_walk(object, inward_winding, medium, x1, dir, roulette, stream, exit);
    if (end == RANDOM_WALK_END_EXITED) {
        precise vec3 l = (entry_weight * exit.weight)
            * random_walk_incident(exit.point, exit.normal, exit.diffuse, exit.direction, stream);
        radiance = l;
    }
    return end;
}

#endif
