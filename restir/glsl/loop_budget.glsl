// Detects loops that the device cut short. Lavapipe (Mesa llvmpipe) gives an invocation group a
// budget of 65 535 loop iterations shared by all of its loops (gallivm's
// LP_MAX_TGSI_LOOP_ITERATIONS) and, once it is spent, ends every loop early without an error. A
// kernel calls this after its work: a loop of two iterations (its bound is a run-time value, so
// it stays a loop) that a spent budget cuts to one. Kernels report a cut (the pass kernels as the
// diag code LOOP_BUDGET_CUT of the engine contract); hosts turn it into an error
// (engine::vulkan::VulkanError::LoopsCut), never into an image.

#ifndef RESTIR_LOOP_BUDGET_GLSL
#define RESTIR_LOOP_BUDGET_GLSL

// `one` must be 1 at run time (e.g. min(width, 1u)) so that the compiler cannot unroll the loop.
bool loop_budget_intact(uint one) {
    uint bound = one + 1u;
    uint iterations = 0u;
    for (uint i = 0u; i < bound; i++) {
        iterations++;
    }
    return iterations == bound;
}

#endif
