// Twin of sss::sampling's disk sampling (sss/src/sampling.rs).

#ifndef SSS_SAMPLING_GLSL
#define SSS_SAMPLING_GLSL

// std::f32::consts::TAU as an f32.
const float SAMPLING_TAU = 6.28318548202514648;

// sample_uniform_disk: r = R sqrt(u1), phi = 2 pi u2 (density 1 / (pi R^2)). `+ × sqrt` match
// the CPU bit for bit; cos and sin are within a few ulp of it.
vec2 sampling_uniform_disk(float radius, float u_radius, float u_angle) {
    precise float r = radius * sqrt(u_radius);
    precise float phi = SAMPLING_TAU * u_angle;
    float c = cos(phi);
    float s = sin(phi);
    precise vec2 p = vec2(r * c, r * s);
    return p;
}

#endif
