// The glam vector operations the scene twins mirror, and the twin of geometry::Frame
// (geometry/src/frame.rs). glam's Vec3 dot is x*x' + y*y' + z*z' left to right, length is
// sqrt(dot), normalize is v * (1 / length), cross is the textbook formula; GLSL's built-in dot,
// length, normalize and cross may be evaluated in another order or fused, so the twins call
// these instead. Every result is `precise`: no multiply-add is fused.

#ifndef SSS_FRAME_GLSL
#define SSS_FRAME_GLSL

float glam_dot(vec3 a, vec3 b) {
    precise float d = a.x * b.x + a.y * b.y + a.z * b.z;
    return d;
}

float glam_length_squared(vec3 v) {
    return glam_dot(v, v);
}

float glam_length(vec3 v) {
    precise float l = sqrt(glam_dot(v, v));
    return l;
}

float glam_distance_squared(vec3 a, vec3 b) {
    precise vec3 d = a - b;
    return glam_dot(d, d);
}

vec3 glam_cross(vec3 a, vec3 b) {
    precise vec3 c = vec3(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
    return c;
}

// Vec3::normalize: v * (1 / |v|) (NaN for a zero vector, as on the CPU).
vec3 glam_normalize(vec3 v) {
    precise float rcp = 1.0 / glam_length(v);
    precise vec3 n = v * rcp;
    return n;
}

// Vec3::try_normalize: false where 1 / |v| is not finite and positive.
bool glam_try_normalize(vec3 v, out vec3 n) {
    precise float rcp = 1.0 / glam_length(v);
    n = vec3(0.0);
    if (isinf(rcp) || isnan(rcp) || !(rcp > 0.0)) {
        return false;
    }
    precise vec3 m = v * rcp;
    n = m;
    return true;
}

// Vec3::normalize_or_zero.
vec3 glam_normalize_or_zero(vec3 v) {
    vec3 n;
    return glam_try_normalize(v, n) ? n : vec3(0.0);
}

// f32::max: the non-NaN operand when one is NaN.
float rust_max(float a, float b) {
    return (a >= b || isnan(b)) ? a : b;
}

// f32::min: the non-NaN operand when one is NaN.
float rust_min(float a, float b) {
    return (a <= b || isnan(b)) ? a : b;
}

// f32::clamp (NaN stays NaN).
float rust_clamp(float x, float lo, float hi) {
    float c = x < lo ? lo : x;
    return c > hi ? hi : c;
}

bool rust_is_finite(float x) {
    return !isinf(x) && !isnan(x);
}

// geometry::Frame: a right-handed orthonormal basis (t, b, n) with t x b = n.
struct Frame {
    vec3 t;
    vec3 b;
    vec3 n;
};

// Frame::from_normal: Duff et al. 2017, Listing 3; the sign is a select (n.z >= 0 gives +1).
Frame frame_from_normal(vec3 n) {
    float sign = n.z >= 0.0 ? 1.0 : -1.0;
    precise float a = -1.0 / (sign + n.z);
    precise float b = n.x * n.y * a;
    Frame f;
    precise vec3 t = vec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    precise vec3 bb = vec3(b, sign + n.y * n.y * a, -n.y);
    f.t = t;
    f.b = bb;
    f.n = n;
    return f;
}

// Frame::to_local.
vec3 frame_to_local(Frame f, vec3 v) {
    return vec3(glam_dot(v, f.t), glam_dot(v, f.b), glam_dot(v, f.n));
}

// Frame::to_world: v.x t + v.y b + v.z n.
vec3 frame_to_world(Frame f, vec3 v) {
    precise vec3 w = v.x * f.t + v.y * f.b + v.z * f.n;
    return w;
}

#endif
