// TPKIT_SYNTH_HOT marks the renderer's inner loops (synth_render.cpp, synth_scene.cpp, synth_terrain.cpp,
// synth_texture.cpp). On x86-64 with GCC each is compiled twice, for the x86-64 baseline and for AVX2, and
// the loader picks the one the CPU runs (target_clones, an ifunc). The AVX2 code is VEX-encoded: three-
// operand arithmetic without the register copies of SSE2's two-operand form, conversions without their false
// dependencies, two more doubles a vector where a loop vectorizes. Both are the same IEEE operations in the same
// order (neither contracts a * b + c into an FMA: AVX2 does not imply FMA), so both give the same pixels.
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__)
#define TPKIT_SYNTH_HOT __attribute__((target_clones("avx2", "default")))
#else
#define TPKIT_SYNTH_HOT
#endif
