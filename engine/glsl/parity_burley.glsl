#version 460
// Parity kernel for sss/glsl/burley.glsl: evaluates the profile at (d, r, u) triples
// (engine/tests/vulkan_parity.rs). `cdf_naive` is the negative control of the test: the
// textbook 1 - e^{-r/d}/4 - 3e^{-r/3d}/4, which loses all digits as r -> 0.
#include "burley.glsl"

layout(local_size_x = 64) in;

struct BurleyInput {
    float d;
    float r;
    float u;
};

struct BurleyOutput {
    float pdf_radius;
    float pdf_disk;
    float cdf;
    float cdf_naive;
    float sample_radius;
};

layout(std430, binding = 0) readonly buffer Inputs { BurleyInput inputs[]; };
layout(std430, binding = 1) writeonly buffer Outputs { BurleyOutput outputs[]; };

layout(push_constant) uniform Params {
    uint count;
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    BurleyInput x = inputs[i];
    BurleyOutput y;
    y.pdf_radius = burley_pdf_radius(x.d, x.r);
    y.pdf_disk = burley_pdf_disk(x.d, x.r);
    y.cdf = burley_cdf(x.d, x.r);
    y.cdf_naive = x.r > 0.0 ? 1.0 - 0.25 * exp(-x.r / x.d) - 0.75 * exp(-x.r / (3.0 * x.d)) : 0.0;
    y.sample_radius = burley_sample_radius(x.d, x.u);
    outputs[i] = y;
}
