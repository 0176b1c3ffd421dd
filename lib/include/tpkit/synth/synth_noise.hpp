// Deterministic hashing and band-limited value noise for the synthetic scene (tp-synth). Everything is a
// pure function of a 64-bit seed and integer lattice coordinates, so rendering does not depend on the
// order of evaluation, strips or threads.
#pragma once
#include <cmath>
#include <cstdint>

namespace tpkit::synth {

// splitmix64 finaliser: a bijective 64-bit mix.
inline uint64_t mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
// Hash of a (pre-mixed) seed and up to three integers: one mix of a linear combination with odd
// 64-bit constants (fast enough to call per lattice point and per sample).
inline uint64_t hash(uint64_t seed, int64_t a, int64_t b = 0, int64_t c = 0) {
  return mix64(seed + static_cast<uint64_t>(a) * 0xd1b54a32d192ed03ULL + static_cast<uint64_t>(b) * 0xaef17502108ef2d9ULL +
               static_cast<uint64_t>(c) * 0xf58e6f2b9c3ab7d5ULL);
}
// Uniform in [0, 1) from a hash.
inline double unit(uint64_t h) { return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0); }
inline double uniform(uint64_t seed, int64_t a, int64_t b = 0, int64_t c = 0) { return unit(hash(seed, a, b, c)); }
// Floor of x as an integer, for |x| < 2^63 (the same value as std::floor, without its library call).
inline int64_t floor_int(double x) {
  const int64_t i = static_cast<int64_t>(x);
  return x < static_cast<double>(i) ? i - 1 : i;
}

// sin(2 pi w) and cos(2 pi w) without the library call: w less its nearest quarter turn n / 4, then Cephes'
// sine and cosine polynomials on [-pi/4, pi/4] (error ~1e-16), the pair picked and signed by n mod 4
// without a branch. They differ from std::sin(2 pi w), std::cos(2 pi w) by less than the rounding of
// 2 pi w itself (2.6e-12 at w = 3000 turns; ~1e-16 for w in [0, 1)).
struct TurnsSinCos {
  int64_t n;  // nearest quarter turn
  double sn, cs;  // sine and cosine of 2 pi (w - n / 4)
};
inline TurnsSinCos turns_sincos(double w) {
  const int64_t n = floor_int(4 * w + 0.5);
  const double x = 2 * 3.14159265358979323846 * (w - 0.25 * static_cast<double>(n)), z = x * x;
  const double sn = x + x * z * (((((1.58962301576546568060E-10 * z - 2.50507477628578072866E-8) * z + 2.75573136213857245213E-6) * z -
                                   1.98412698295895385996E-4) * z + 8.33333333332211858878E-3) * z - 1.66666666666666307295E-1);
  const double cs = 1.0 - 0.5 * z + z * z * (((((-1.13585365213876817300E-11 * z + 2.08757008419747316778E-9) * z -
                                                 2.75573141792967388112E-7) * z + 2.48015872888517045348E-5) * z -
                                               1.38888888888730564116E-3) * z + 4.16666666666665929218E-2);
  return {n, sn, cs};
}
// sin(2 pi w): n mod 4 = 0, 1, 2, 3 gives sn, cs, -sn, -cs.
inline double sin_turns(double w) {
  const TurnsSinCos t = turns_sincos(w);
  const double pick[2] = {t.sn, t.cs};
  return pick[t.n & 1] * static_cast<double>(1 - (t.n & 2));
}
// cos(2 pi w): n mod 4 = 0, 1, 2, 3 gives cs, -sn, -cs, sn.
inline double cos_turns(double w) {
  const TurnsSinCos t = turns_sincos(w);
  const double pick[2] = {t.cs, t.sn};
  return pick[t.n & 1] * static_cast<double>(1 - ((t.n + 1) & 2));
}

// Standard normal deviate from a hash (Box-Muller on two 53-bit uniforms, the first in (0, 1]); the cosine
// by cos_turns (std::cos(2 pi u2) to ~1e-16: a sensor noise of a few DN moves by ~1e-15 DN).
// normal(h) in two halves (a renderer's row runs each over its pixels in a pass): the two uniforms from the
// hash, then the deviate from them.
inline void normal_uniforms(uint64_t h, double& u1, double& u2) {
  u1 = (static_cast<double>(mix64(h) >> 11) + 1) * (1.0 / 9007199254740993.0);
  u2 = unit(mix64(h ^ 0xabcdef12345ULL));
}
inline double normal_from(double u1, double u2) { return std::sqrt(-2 * std::log(u1)) * cos_turns(u2); }
inline double normal(uint64_t h) {
  double u1, u2;
  normal_uniforms(h, u1, u2);
  return normal_from(u1, u2);
}

// 0 below e0, 1 above e1 (e0 < e1), the cubic smoothstep between; outside the ramp, where most samples
// lie, without the division (the same values). Inside, e0 < x < e1 gives 0 <= x - e0 <= e1 - e0 after
// rounding (it is monotonic), so t is in [0, 1] without a clamp.
inline double smoothstep(double e0, double e1, double x) {
  if (x <= e0) return 0;
  if (x >= e1) return 1;
  const double t = (x - e0) / (e1 - e0);
  return t * t * (3 - 2 * t);
}
inline double lerp(double a, double b, double t) { return a + (b - a) * t; }

// The four hashed lattice values of one cell of a value noise, kept between calls (value_noise below):
// consecutive samples of a rendering mostly fall in the same cell.
struct NoiseCell {
  bool valid = false;
  uint64_t seed = 0;
  int64_t ix = 0, iy = 0;
  double v00 = 0, v10 = 0, v01 = 0, v11 = 0;
};

// 2-D value noise in [-1, 1] on the unit lattice with quintic (C2) interpolation of hashed lattice values:
// continuous with continuous first and second derivatives; its spectrum is concentrated below 1 cycle per
// lattice unit. `cell` holds the last cell's lattice values (the same values as hashing them afresh).
inline double value_noise(uint64_t seed, double x, double y, NoiseCell& cell) {
  const int64_t ix = floor_int(x), iy = floor_int(y);
  const double tx = x - static_cast<double>(ix), ty = y - static_cast<double>(iy);
  const double sx = tx * tx * tx * (tx * (tx * 6 - 15) + 10);
  const double sy = ty * ty * ty * (ty * (ty * 6 - 15) + 10);
  if (!cell.valid || cell.ix != ix || cell.iy != iy || cell.seed != seed) {
    // hash(seed, ix + a, iy + b) for a, b in {0, 1}, sharing the products (the same values as four hash calls)
    const uint64_t h00 = seed + static_cast<uint64_t>(ix) * 0xd1b54a32d192ed03ULL + static_cast<uint64_t>(iy) * 0xaef17502108ef2d9ULL;
    const uint64_t h10 = h00 + 0xd1b54a32d192ed03ULL, h01 = h00 + 0xaef17502108ef2d9ULL, h11 = h10 + 0xaef17502108ef2d9ULL;
    const bool row = cell.valid && cell.seed == seed && cell.iy == iy;
    if (row && ix == cell.ix + 1) {  // the next cell along x (a rendered row's usual step): two values are the last's
      cell.v00 = cell.v10;
      cell.v01 = cell.v11;
      cell.v10 = 2 * unit(mix64(h10)) - 1;
      cell.v11 = 2 * unit(mix64(h11)) - 1;
      cell.ix = ix;
    } else if (row && ix == cell.ix - 1) {
      cell.v10 = cell.v00;
      cell.v11 = cell.v01;
      cell.v00 = 2 * unit(mix64(h00)) - 1;
      cell.v01 = 2 * unit(mix64(h01)) - 1;
      cell.ix = ix;
    } else {
      cell = {true, seed, ix, iy, 2 * unit(mix64(h00)) - 1, 2 * unit(mix64(h10)) - 1, 2 * unit(mix64(h01)) - 1,
              2 * unit(mix64(h11)) - 1};
    }
  }
  return lerp(lerp(cell.v00, cell.v10, sx), lerp(cell.v01, cell.v11, sx), sy);
}
inline double value_noise(uint64_t seed, double x, double y) {
  NoiseCell cell;
  return value_noise(seed, x, y, cell);
}

}  // namespace tpkit::synth
