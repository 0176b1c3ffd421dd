// TPKIT_HOT marks an inner loop worth compiling twice: on x86-64 with GCC, once for the x86-64 baseline
// and once for AVX2, the loader picking the one the CPU runs (target_clones, an ifunc); elsewhere it is an
// ordinary function. The AVX2 code is VEX-encoded (three-operand arithmetic, no false dependencies in
// conversions) and vectorizes loops four doubles, eight floats or sixteen shorts wide. Both clones do the
// same IEEE operations in the same order (neither contracts a * b + c into an FMA: AVX2 does not imply
// FMA, and GCC does not reassociate without -ffast-math), so results do not depend on the CPU.
// Users: the synthetic renderer (synth_render, synth_scene, synth_terrain, synth_texture: the same
// pixels) and the guided descriptor search (guided_matching: the same matches).
//
// TPKIT_AVX2 marks a function compiled for AVX2 alone, for code written at two vector widths (GCC's
// vector extension, 16 bytes in the baseline version, 32 in the AVX2 one) that cpu_has_avx2() chooses
// between at run time; the same rule holds (no FMA, the same operations in the same order in each lane).
// Where TPKIT_HOT is an ordinary function, TPKIT_HAS_AVX2 is 0 and cpu_has_avx2() false.
// Users: the Gaussian blur of the SIFT scale space (gaussian_blur); the guided search's descriptor
// distances (guided_matching, AVX2 intrinsics: the same integers).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__)
#define TPKIT_HOT __attribute__((target_clones("avx2", "default")))
#define TPKIT_HAS_AVX2 1
#define TPKIT_AVX2 __attribute__((target("avx2")))
namespace tpkit {
inline bool cpu_has_avx2() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
}
}  // namespace tpkit
#else
#define TPKIT_HOT
#define TPKIT_HAS_AVX2 0
#define TPKIT_AVX2
namespace tpkit {
inline bool cpu_has_avx2() { return false; }
}  // namespace tpkit
#endif

namespace tpkit {
// Asks the memory for the n floats from p, one request per 64-byte cache line, and returns at once: for
// a loop that will read rows lying a plane's width apart, a few rows before it reads them (the hardware
// prefetchers follow one row, not the jump to the next). No effect on any value.
// Users: the Gaussian blur, the SIFT extremum scan, orientations and descriptors (sift_scale_space).
// On x86-64 the request is an asm statement: GCC treats __builtin_prefetch as free of effects and,
// once such a loop was inlined into the descriptor's, dropped it whole (-O2, and -O3 there).
inline void prefetch_floats(const float* p, long n) {
  for (long i = 0; i < n; i += 16) {
#if defined(__x86_64__) && defined(__GNUC__)
    asm volatile("prefetcht0 %0" : : "m"(p[i]));
#else
    __builtin_prefetch(p + i);
#endif
  }
}
}  // namespace tpkit
