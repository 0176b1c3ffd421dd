// TPKIT_HOT marks an inner loop worth compiling twice: on x86-64 with GCC, once for the x86-64 baseline
// and once for AVX2, the loader picking the one the CPU runs (target_clones, an ifunc); elsewhere it is an
// ordinary function. The AVX2 code is VEX-encoded (three-operand arithmetic, no false dependencies in
// conversions) and vectorizes loops four doubles, eight floats or sixteen shorts wide. Both clones do the
// same IEEE operations in the same order (neither contracts a * b + c into an FMA: AVX2 does not imply
// FMA, and GCC does not reassociate without -ffast-math), so results do not depend on the CPU.
// Users: the synthetic renderer (synth_render, synth_scene, synth_terrain, synth_texture: the same
// pixels) and the guided descriptor search (guided_matching: the same matches).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__)
#define TPKIT_HOT __attribute__((target_clones("avx2", "default")))
#else
#define TPKIT_HOT
#endif
