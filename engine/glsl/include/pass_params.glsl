// The push constants of every pass kernel: the GLSL twin of engine::vulkan::PassParams
// (32 bytes; docs/gpu-backend.md). `shift` indexes ShiftKind::ALL, `mis` follows MisKind's
// declaration order, `confidence_cap` <= 0 means none.

#ifndef EXPERIMENTS_PASS_PARAMS_GLSL
#define EXPERIMENTS_PASS_PARAMS_GLSL

layout(push_constant) uniform PassParams {
    uint pass;
    uint shift;
    uint mis;
    uint neighbours;
    float confidence_cap;
    uint bssrdf_samples;
    uint shared_light;
    uint collect_diagnostics;
} params;

#endif
