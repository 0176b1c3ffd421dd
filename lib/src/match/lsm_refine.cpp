#include "tpkit/match/lsm_refine.hpp"

#include "tpkit/core/cpu_dispatch.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>
#include <vector>

namespace tpkit {

const char* to_string(LsmStatus s) {
  switch (s) {
    case LsmStatus::Ok: return "ok";
    case LsmStatus::OutOfImage: return "out-of-image";
    case LsmStatus::Invalid: return "nodata";
    case LsmStatus::Flat: return "flat";
    case LsmStatus::Diverged: return "diverged";
    case LsmStatus::NotConverged: return "not-converged";
    case LsmStatus::Drifted: return "drifted";
    case LsmStatus::LowCorrelation: return "low-correlation";
    case LsmStatus::Imprecise: return "imprecise";
    case LsmStatus::OffEpipolar: return "off-epipolar";
  }
  return "?";
}

namespace {
// Keys (a = -0.5) weights of the samples at offsets -1, 0, 1, 2 for the fractional position t in [0, 1),
// and their derivatives d/dt.
inline void keys(double t, double w[4], double dw[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = -0.5 * t3 + t2 - 0.5 * t;
  w[1] = 1.5 * t3 - 2.5 * t2 + 1;
  w[2] = -1.5 * t3 + 2 * t2 + 0.5 * t;
  w[3] = 0.5 * t3 - 0.5 * t2;
  dw[0] = -1.5 * t2 + 2 * t - 0.5;
  dw[1] = 4.5 * t2 - 5 * t;
  dw[2] = -4.5 * t2 + 4 * t + 0.5;
  dw[3] = 1.5 * t2 - t;
}

// Bicubic value and gradient at local (lx, ly) of r; false outside the support or on NaN.
inline bool bicubic_local(const Raster& r, double lx, double ly, double& value, double& gx, double& gy) {
  const double fx = std::floor(lx), fy = std::floor(ly);
  const long ix = static_cast<long>(fx), iy = static_cast<long>(fy);
  if (ix < 1 || iy < 1 || ix + 2 >= r.width || iy + 2 >= r.height) return false;
  double wx[4], dwx[4], wy[4], dwy[4];
  keys(lx - fx, wx, dwx);
  keys(ly - fy, wy, dwy);
  const float* row = r.data.data() + static_cast<size_t>(iy - 1) * r.width + (ix - 1);
  double v = 0, vx = 0, vy = 0;
  for (int j = 0; j < 4; ++j, row += r.width) {
    const double a0 = row[0], a1 = row[1], a2 = row[2], a3 = row[3];
    const double s = wx[0] * a0 + wx[1] * a1 + wx[2] * a2 + wx[3] * a3;
    const double sx = dwx[0] * a0 + dwx[1] * a1 + dwx[2] * a2 + dwx[3] * a3;
    v += wy[j] * s;
    vx += wy[j] * sx;
    vy += dwy[j] * s;
  }
  if (std::isnan(v)) return false;
  value = v;
  gx = vx;
  gy = vy;
  return true;
}

// Fast bicubic for the Gauss-Newton loop: the 4 x 4 neighbourhood in single precision, 4 taps of a row
// at a time (GCC/Clang vector extensions: SSE on x86-64, NEON on ARM, scalar code elsewhere), the Keys
// weights of both axes by Horner's rule on 4-vectors (no branches). Single precision costs ~1e-3 grey
// levels of a 12-bit image, far below the noise; the result is returned in double.
typedef float v4f __attribute__((vector_size(16)));
inline v4f load4(const float* p) {
  v4f r;
  std::memcpy(&r, p, sizeof r);
  return r;
}
inline float hsum(v4f a) { return (a[0] + a[1]) + (a[2] + a[3]); }
// Grad = false: the value only (the same value, by the same operations), for the pixels that only
// enter the grey-level normalisation and the correlation.
template <bool Grad>
inline bool bicubic_fast(const Raster& r, double lx, double ly, double& value, double& gx, double& gy) {
  // same support as bicubic_local (floor(lx) in [1, width - 3]); false also for NaN positions
  if (!(lx >= 1 && ly >= 1 && lx < static_cast<double>(r.width - 2) && ly < static_cast<double>(r.height - 2))) return false;
  const long ix = static_cast<long>(lx), iy = static_cast<long>(ly);
  const float tx = static_cast<float>(lx - static_cast<double>(ix)), ty = static_cast<float>(ly - static_cast<double>(iy));
  // w(t) = ((C3 t + C2) t + C1) t + C0, w'(t) = (3 C3 t + 2 C2) t + C1 (taps -1, 0, 1, 2)
  const v4f C0 = {0, 1, 0, 0}, C1 = {-0.5f, 0, 0.5f, 0}, C2 = {1, -2.5f, 2, -0.5f}, C3 = {-0.5f, 1.5f, -1.5f, 0.5f};
  const v4f D2 = {-1.5f, 4.5f, -4.5f, 1.5f}, D1 = {2, -5, 4, -1};
  const v4f wx = ((C3 * tx + C2) * tx + C1) * tx + C0;
  const v4f wy = ((C3 * ty + C2) * ty + C1) * ty + C0;
  const long W = r.width;
  const float* p = r.data.data() + static_cast<size_t>(iy - 1) * W + (ix - 1);
  const v4f R0 = load4(p), R1 = load4(p + W), R2 = load4(p + 2 * W), R3 = load4(p + 3 * W);
  const v4f S = (R0 * wy[0] + R1 * wy[1]) + (R2 * wy[2] + R3 * wy[3]);
  const float v = hsum(S * wx);
  if (std::isnan(v)) return false;
  value = v;
  if constexpr (Grad) {
    const v4f dwx = (D2 * tx + D1) * tx + C1, dwy = (D2 * ty + D1) * ty + C1;
    const v4f Sy = (R0 * dwy[0] + R1 * dwy[1]) + (R2 * dwy[2] + R3 * dwy[3]);
    gx = hsum(S * dwx);
    gy = hsum(Sy * wx);
  }
  return true;
}

// bicubic_fast at the local positions (qx[k], qy[k]), k in [a, b): values (and with Grad gradients)
// into val, gx, gy; false at a position outside the support or a NaN value (the caller then gives the
// window up, whatever was written).
template <bool Grad>
inline bool bicubic_each(const Raster& r, const double* qx, const double* qy, int a, int b, double* val, double* gx, double* gy) {
  for (int k = a; k < b; ++k)
    if (!bicubic_fast<Grad>(r, qx[k], qy[k], val[k], gx[k], gy[k])) return false;
  return true;
}

#if TPKIT_HAS_AVX2
// The same, two positions at a time, one in each half of 8-float vectors: lane by lane the operations of
// bicubic_fast in the same order (no FMA), so the same values; half the instructions and two independent
// chains of them (the value's chain of loads, products and horizontal sums was where a pixel waited).
typedef float v8f __attribute__((vector_size(32)));
typedef int v8i __attribute__((vector_size(32)));
TPKIT_AVX2 [[gnu::always_inline]] inline v8f lanes(const v8f& a, int i) {  // element i of each half, in all of that half
  return __builtin_shuffle(a, v8i{i, i, i, i, 4 + i, 4 + i, 4 + i, 4 + i});
}
// (a0 + a1) + (a2 + a3) of each half, in elements 0 and 4
TPKIT_AVX2 [[gnu::always_inline]] inline v8f hsum2(const v8f& a) {
  const v8f t = a + __builtin_shuffle(a, v8i{1, 0, 3, 2, 5, 4, 7, 6});
  return t + __builtin_shuffle(t, v8i{2, 3, 0, 1, 6, 7, 4, 5});
}
template <bool Grad>
TPKIT_AVX2 bool bicubic_pairs_avx2(const Raster& r, const double* qx, const double* qy, int a, int b, double* val, double* gx,
                                   double* gy) {
  const double xmax = static_cast<double>(r.width - 2), ymax = static_cast<double>(r.height - 2);
  const long W = r.width;
  const v8f C0 = {0, 1, 0, 0, 0, 1, 0, 0}, C1 = {-0.5f, 0, 0.5f, 0, -0.5f, 0, 0.5f, 0}, C2 = {1, -2.5f, 2, -0.5f, 1, -2.5f, 2, -0.5f},
            C3 = {-0.5f, 1.5f, -1.5f, 0.5f, -0.5f, 1.5f, -1.5f, 0.5f};
  const v8f D2 = {-1.5f, 4.5f, -4.5f, 1.5f, -1.5f, 4.5f, -4.5f, 1.5f}, D1 = {2, -5, 4, -1, 2, -5, 4, -1};
  int k = a;
  for (; k + 1 < b; k += 2) {
    const double x0 = qx[k], y0 = qy[k], x1 = qx[k + 1], y1 = qy[k + 1];
    if (!(x0 >= 1 && y0 >= 1 && x0 < xmax && y0 < ymax && x1 >= 1 && y1 >= 1 && x1 < xmax && y1 < ymax)) return false;
    const long ix0 = static_cast<long>(x0), iy0 = static_cast<long>(y0), ix1 = static_cast<long>(x1), iy1 = static_cast<long>(y1);
    const float tx0 = static_cast<float>(x0 - static_cast<double>(ix0)), ty0 = static_cast<float>(y0 - static_cast<double>(iy0));
    const float tx1 = static_cast<float>(x1 - static_cast<double>(ix1)), ty1 = static_cast<float>(y1 - static_cast<double>(iy1));
    const v8f tx = {tx0, tx0, tx0, tx0, tx1, tx1, tx1, tx1}, ty = {ty0, ty0, ty0, ty0, ty1, ty1, ty1, ty1};
    const v8f wx = ((C3 * tx + C2) * tx + C1) * tx + C0, wy = ((C3 * ty + C2) * ty + C1) * ty + C0;
    const float* p0 = r.data.data() + static_cast<size_t>(iy0 - 1) * W + (ix0 - 1);
    const float* p1 = r.data.data() + static_cast<size_t>(iy1 - 1) * W + (ix1 - 1);
    v8f R[4];
    for (int j = 0; j < 4; ++j) R[j] = __builtin_shufflevector(load4(p0 + j * W), load4(p1 + j * W), 0, 1, 2, 3, 4, 5, 6, 7);
    const v8f S = (R[0] * lanes(wy, 0) + R[1] * lanes(wy, 1)) + (R[2] * lanes(wy, 2) + R[3] * lanes(wy, 3));
    const v8f v = hsum2(S * wx);
    if (std::isnan(v[0]) || std::isnan(v[4])) return false;
    val[k] = v[0];
    val[k + 1] = v[4];
    if constexpr (Grad) {
      const v8f dwx = (D2 * tx + D1) * tx + C1, dwy = (D2 * ty + D1) * ty + C1;
      const v8f Sy = (R[0] * lanes(dwy, 0) + R[1] * lanes(dwy, 1)) + (R[2] * lanes(dwy, 2) + R[3] * lanes(dwy, 3));
      const v8f hx = hsum2(S * dwx), hy = hsum2(Sy * wx);
      gx[k] = hx[0], gx[k + 1] = hx[4];
      gy[k] = hy[0], gy[k + 1] = hy[4];
    }
  }
  return bicubic_each<Grad>(r, qx, qy, k, b, val, gx, gy);
}
#endif

template <bool Grad>
bool bicubic_batch(const Raster& r, const double* qx, const double* qy, int a, int b, double* val, double* gx, double* gy,
                   bool baseline) {
#if TPKIT_HAS_AVX2
  if (!baseline && cpu_has_avx2()) return bicubic_pairs_avx2<Grad>(r, qx, qy, a, b, val, gx, gy);
#endif
  (void)baseline;
  return bicubic_each<Grad>(r, qx, qy, a, b, val, gx, gy);
}
}  // namespace

bool bicubic(const Raster& r, double x, double y, double& value, double* gx, double* gy) {
  double vx, vy;
  if (!bicubic_local(r, x - r.x0, y - r.y0, value, vx, vy)) return false;
  if (gx) *gx = vx;
  if (gy) *gy = vy;
  return true;
}
namespace {
// The sum of f(k), k in [0, n), in four interleaved partial sums: four chains of additions side by side
// instead of one (the window's statistics: one chain of 441 dependent additions each took longer than
// the arithmetic around it). Another order than one by one: the values move by rounding only (on the
// 10000² pair, refined positions by 2e-6 px at most, no acceptance changed).
template <class F>
inline double sum4(int n, F f) {
  double a[4] = {0, 0, 0, 0};
  int k = 0;
  for (; k + 4 <= n; k += 4)
    for (int j = 0; j < 4; ++j) a[j] += f(k + j);
  for (; k < n; ++k) a[0] += f(k);
  return (a[0] + a[1]) + (a[2] + a[3]);
}

constexpr int kMaxP = 14;  // p2 (2), A (4), r0, r1, quadratic terms (6)

// Per-thread scratch, so that a call allocates nothing once the thread has seen the window size.
// Pixels are held in order of increasing distance of their integer offset from the window centre, so
// that the pixels within a radius are a prefix.
struct Scratch {
  int w = -1;
  std::vector<int> oi, oj, or2;  // integer offsets from the centre pixel, and their squared radius
  std::vector<int> ci, cj, cidx;  // a window cut at an image's edge: its pixels' offsets, their indices in oi
  std::vector<double> du, dv, t, tap, g, gx, gy, r, wt;
  std::vector<double> qx, qy;  // image 2's positions under the model being evaluated, local pixels
  std::vector<double> taper_u, taper_v;  // the taper's factors along u and v, by integer offset + h
  void prepare(int win) {
    if (win == w) return;
    w = win;
    const int h = w / 2, n = w * w;
    std::vector<int> idx(n);
    for (int k = 0; k < n; ++k) idx[k] = k;
    auto r2 = [&](int k) { return (k % w - h) * (k % w - h) + (k / w - h) * (k / w - h); };
    std::stable_sort(idx.begin(), idx.end(), [&](int a, int b) { return r2(a) < r2(b); });
    oi.resize(n), oj.resize(n), or2.resize(n), ci.resize(n), cj.resize(n), cidx.resize(n);
    for (int k = 0; k < n; ++k) oi[k] = idx[k] % w - h, oj[k] = idx[k] / w - h, or2[k] = r2(idx[k]);
    for (auto* v : {&du, &dv, &t, &tap, &g, &gx, &gy, &r, &wt, &qx, &qy}) v->resize(n);
    taper_u.resize(w), taper_v.resize(w);
  }
  // number of pixels within `radius` of the centre pixel
  int within(double radius) const {
    const double R2 = radius * radius;
    return static_cast<int>(std::upper_bound(or2.begin(), or2.end(), R2, [](double x, int v) { return x < v; }) - or2.begin());
  }
};

// Lower triangle of the normal matrix (row-major) and the right-hand side, P parameters.
template <int P>
struct Normal {
  double N[P * (P + 1) / 2];
  double b[P];
};

// Accumulates the weighted normal equations of the first m pixels. Jacobian row of the residual
// r = r0 + r1 g(q(d)) - t: r1 gx (1, u, v), r1 gy (1, u, v) in the order p2x, p2y, a11, a12, a21, a22;
// then 1, g; then (P = 14) r1 gx (U, W, V), r1 gy (U, W, V) with U = qs u^2, W = qs u v, V = qs v^2.
// P = 11: the curvature terms act along the unit direction e (image 2): r1 (gx ex + gy ey) (U, W, V).
template <int P>
void accumulate(const Scratch& s, int m, double r1, double qs, Normal<P>& ne, bool with_b, double ex = 0, double ey = 0) {
  std::fill(std::begin(ne.N), std::end(ne.N), 0.0);
  std::fill(std::begin(ne.b), std::end(ne.b), 0.0);
  double j[P];
  for (int k = 0; k < m; ++k) {
    const double u = s.du[k], v = s.dv[k];
    const double ax = r1 * s.gx[k], ay = r1 * s.gy[k];
    j[0] = ax;
    j[1] = ay;
    j[2] = ax * u;
    j[3] = ax * v;
    j[4] = ay * u;
    j[5] = ay * v;
    j[6] = 1.0;
    j[7] = s.g[k];
    if constexpr (P == 11) {
      const double ae = ax * ex + ay * ey;
      j[8] = ae * qs * u * u;
      j[9] = ae * qs * u * v;
      j[10] = ae * qs * v * v;
    } else if constexpr (P > 8) {
      const double U = qs * u * u, W = qs * u * v, V = qs * v * v;
      j[8] = ax * U;
      j[9] = ax * W;
      j[10] = ax * V;
      j[11] = ay * U;
      j[12] = ay * W;
      j[13] = ay * V;
    }
    const double w = s.wt[k];
    int e = 0;
    for (int a = 0; a < P; ++a) {
      const double wa = w * j[a];
      if (with_b) ne.b[a] += wa * s.r[k];
      for (int c = 0; c <= a; ++c) ne.N[e++] += wa * j[c];
    }
  }
}

// The Gauss-Newton iterations of the affine model: the normal matrix in single precision, four pixels at a
// time (it steers the steps and gives the covariance: its rounding, ~1e-6 relative, changes the path by far
// less than the tolerance), the right-hand side J^T W r in double (it fixes the solution), two pixels at a
// time. Fixed lane order: deterministic.
typedef double v2d __attribute__((vector_size(16)));
void accumulate8_fast(const Scratch& s, int m, double r1, Normal<8>& ne) {
  v4f N[36];
  v2d B[16];
  for (auto& x : N) x = v4f{0, 0, 0, 0};
  for (auto& x : B) x = v2d{0, 0};
  const float r1f = static_cast<float>(r1);
  auto step = [&](const double* u, const double* v, const double* gx, const double* gy, const double* g, const double* r,
                  const double* w) {
    for (int h = 0; h < 2; ++h) {  // right-hand side, double, two pixels at a time
      const int o = 2 * h;
      const v2d U = {u[o], u[o + 1]}, V = {v[o], v[o + 1]}, G = {g[o], g[o + 1]};
      const v2d ax = r1 * v2d{gx[o], gx[o + 1]}, ay = r1 * v2d{gy[o], gy[o + 1]};
      const v2d wr = v2d{w[o], w[o + 1]} * v2d{r[o], r[o + 1]};
      v2d* b = B + 8 * h;
      b[0] += wr * ax;
      b[1] += wr * ay;
      b[2] += wr * (ax * U);
      b[3] += wr * (ax * V);
      b[4] += wr * (ay * U);
      b[5] += wr * (ay * V);
      b[6] += wr;
      b[7] += wr * G;
    }
    auto f4 = [](const double* a) { return v4f{static_cast<float>(a[0]), static_cast<float>(a[1]), static_cast<float>(a[2]), static_cast<float>(a[3])}; };
    const v4f U = f4(u), V = f4(v), G = f4(g), W = f4(w);
    const v4f ax = r1f * f4(gx), ay = r1f * f4(gy);
    const v4f j[8] = {ax, ay, ax * U, ax * V, ay * U, ay * V, v4f{1, 1, 1, 1}, G};
    int e = 0;
#pragma GCC unroll 8
    for (int a = 0; a < 8; ++a) {
      const v4f wa = W * j[a];
#pragma GCC unroll 8
      for (int c = 0; c <= a; ++c) N[e++] += wa * j[c];
    }
  };
  const double *pu = s.du.data(), *pv = s.dv.data(), *pgx = s.gx.data(), *pgy = s.gy.data(), *pg = s.g.data(),
               *pr = s.r.data(), *pw = s.wt.data();
  int k = 0;
  for (; k + 3 < m; k += 4) step(pu + k, pv + k, pgx + k, pgy + k, pg + k, pr + k, pw + k);
  if (k < m) {  // the last 1..3 pixels, padded with zero weights
    double t[7][4] = {};
    for (int i = 0; k + i < m; ++i)
      t[0][i] = pu[k + i], t[1][i] = pv[k + i], t[2][i] = pgx[k + i], t[3][i] = pgy[k + i], t[4][i] = pg[k + i],
      t[5][i] = pr[k + i], t[6][i] = pw[k + i];
    step(t[0], t[1], t[2], t[3], t[4], t[5], t[6]);
  }
  for (int e = 0; e < 36; ++e)
    ne.N[e] = (static_cast<double>(N[e][0]) + static_cast<double>(N[e][1])) + (static_cast<double>(N[e][2]) + static_cast<double>(N[e][3]));
  for (int a = 0; a < 8; ++a) ne.b[a] = (B[a][0] + B[a][1]) + (B[8 + a][0] + B[8 + a][1]);
}

// N = L D L^T of a normal matrix (its packed lower triangle), unpivoted: J^T W J is symmetric positive
// definite, for which the unpivoted factorisation is stable; a degenerate window (a pivot not positive)
// is refused. Written out for the fixed P: Eigen's pivoting LDLT of an 8 x 8 matrix took ~5% of the refinement.
template <int P>
struct Ldl {
  double L[P][P], D[P];
  bool factor(const Normal<P>& ne) {
    for (int a = 0, row = 0; a < P; row += ++a)  // row a of the packed triangle starts at a (a + 1) / 2
      for (int c = 0; c <= a; ++c) {
        double v = ne.N[row + c];
        for (int k = 0; k < c; ++k) v -= L[a][k] * D[k] * L[c][k];
        if (c < a) {
          L[a][c] = v / D[c];
        } else {
          if (!(v > 0)) return false;
          D[a] = v;
        }
      }
    return true;
  }
  // x <- N^-1 x
  void solve(double* x) const {
    for (int a = 1; a < P; ++a)
      for (int k = 0; k < a; ++k) x[a] -= L[a][k] * x[k];
    for (int a = 0; a < P; ++a) x[a] /= D[a];
    for (int a = P - 2; a >= 0; --a)
      for (int k = a + 1; k < P; ++k) x[a] -= L[k][a] * x[k];
  }
};

// Gauss-Newton step of the first P parameters; false when the system is singular or the step not finite.
template <int P>
bool gn_step(const Normal<P>& ne, Eigen::Matrix<double, kMaxP, 1>& delta) {
  Ldl<P> f;
  if (!f.factor(ne)) return false;
  double d[P];
  for (int a = 0; a < P; ++a) d[a] = -ne.b[a];
  f.solve(d);
  delta.setZero();
  for (int a = 0; a < P; ++a) delta(a) = d[a];
  return delta.allFinite();
}

// (C(0, 0) + C(1, 1)) / 2 of C = N^-1: the mean variance of p2's coordinates up to sigma0^2; infinite
// when N is singular
template <int P>
double var_p2(const Normal<P>& ne) {
  Ldl<P> f;
  if (!f.factor(ne)) return std::numeric_limits<double>::infinity();
  double e0[P] = {1}, e1[P] = {0, 1};
  f.solve(e0);
  f.solve(e1);
  return 0.5 * (e0[0] + e1[1]);
}
// Covariance of p2 by the sandwich of taper-weighted least squares at the solution, over the pixels
// with keep[k] > 0 (their taper weights): C = B^-1 M B^-1, B = sum keep J^T J, M = sum keep^2 J^T J, times
// the weighted residual variance; returns the 2 x 2 block of p2 (Sandwich: C and the factor's terms apart, so
// that var() is computed in the order it always was), infinite when B is singular. (The
// IRLS normal matrix with the L1 weights taper / |r| is no covariance: its small residuals' large
// weights make it 5x too optimistic on white noise.) Overwrites s.wt (left as keep).
struct Sandwich {
  Eigen::Matrix2d C = Eigen::Matrix2d::Constant(std::numeric_limits<double>::infinity());
  double swr2 = 1, sw = 1;  // the factor swr2 / sw * kept / (kept - P)
  int kept = 1, P = 0;
  double var() const { return 0.5 * (C(0, 0) + C(1, 1)) * swr2 / sw * kept / (kept - P); }
  Eigen::Matrix2d cov() const { return C * (swr2 / sw * kept / (kept - P)); }
};
template <int P>
Sandwich sandwich_cov_p2(Scratch& s, int m, double r1, double qs, double ex, double ey, const std::vector<double>& keep) {
  const Sandwich none;
  Normal<P> ne;
  auto full = [&](const Normal<P>& x) {
    Eigen::Matrix<double, P, P> F;
    for (int a = 0, row = 0; a < P; row += ++a)
      for (int c = 0; c <= a; ++c) F(a, c) = F(c, a) = x.N[row + c];
    return F;
  };
  double sw = 0, swr2 = 0;
  int kept = 0;
  for (int k = 0; k < m; ++k) {
    s.wt[k] = keep[k] * keep[k];
    sw += keep[k], swr2 += keep[k] * s.r[k] * s.r[k], kept += keep[k] > 0;
  }
  accumulate<P>(s, m, r1, qs, ne, false, ex, ey);
  const Eigen::Matrix<double, P, P> M = full(ne);
  for (int k = 0; k < m; ++k) s.wt[k] = keep[k];
  accumulate<P>(s, m, r1, qs, ne, false, ex, ey);
  const Eigen::Matrix<double, P, P> B = full(ne);
  if (kept <= P || !(sw > 0)) return none;
  Eigen::LDLT<Eigen::Matrix<double, P, P>> f(B);
  if (f.info() != Eigen::Success || !f.isPositive()) return none;
  const Eigen::Matrix<double, P, 2> Bi = f.solve(Eigen::Matrix<double, P, P>::Identity().template leftCols<2>());
  Sandwich out;
  out.C = Bi.transpose() * M * Bi;
  out.swr2 = swr2, out.sw = sw, out.kept = kept, out.P = P;
  return out;
}
// The sandwich covariance of p2 for the model of P parameters at the current state, over the support's
// pixels with their taper weights, those the fit's mask (LsmOptions::mask_fit_k) left out included: their
// residuals are what the position did not explain, and over the kept pixels alone (a spread cut at the
// mask) the sigma fell below the error on tp-synth truth (error / sigma 1.08..1.52 in the deciles of the
// default scene, 0.85..1.16 over them all).
template <int P>
Sandwich sandwich_cov_support(Scratch& s, int m, double r1, double qs, double ex, double ey) {
  return sandwich_cov_p2<P>(s, m, r1, qs, ex, ey, s.tap);
}

// Residual mask: the threshold k x 1.4826 x median |r| over the first m pixels (a robust scale of the
// residuals, which a minority of changed pixels does not inflate; infinite when k <= 0: no mask), and
// (mask_residuals) zero weight beyond a threshold.
double mask_threshold(const Scratch& s, int m, double k, std::vector<double>& buf) {
  if (!(k > 0) || m < 8) return std::numeric_limits<double>::infinity();
  buf.resize(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) buf[static_cast<size_t>(i)] = std::abs(s.r[i]);
  std::nth_element(buf.begin(), buf.begin() + m / 2, buf.end());
  return k * 1.4826 * std::max(buf[static_cast<size_t>(m / 2)], 1e-6);
}
void mask_residuals(Scratch& s, int m, double thr) {
  for (int i = 0; i < m; ++i)
    if (std::abs(s.r[i]) > thr) s.wt[i] = 0;
}
// A window at an image's edge (LsmOptions::edge_share): the window's pixels inside image 1 whose image-2
// position under (p2, A0) lies at least max_shift + 1 px inside the interpolation's bounds, copied in
// order of radius to s.ci, s.cj (their indices in s.oi to s.cidx). Returns how many: all of the window's
// (w^2) when the whole window lies within both images (then nothing is cut), 0 when those kept hold less
// than edge_share of the support's taper weight.
int cut_window_at_edges(Scratch& s, const Raster& img1, const Raster& img2, long cx, long cy, double fx, double fy,
                        const Eigen::Vector2d& p2, const Eigen::Matrix2d& A0, const LsmOptions& o) {
  const int n = static_cast<int>(s.oi.size());
  const double margin = o.max_shift + 1;
  // bicubic_local reads 1 pixel before and 2 after the position's floor
  const double x_lo = 1 + margin, y_lo = 1 + margin, x_hi = img2.width - 2 - margin, y_hi = img2.height - 2 - margin;
  const double ox = p2.x() - img2.x0, oy = p2.y() - img2.y0;
  const double sg = o.taper, support = o.quadratic ? o.quadratic_support : o.support;
  const int m = sg > 0 && support > 0 ? std::min(n, s.within(support * sg)) : n;
  const double den = sg > 0 ? 1.0 / (2 * sg * sg) : 0.0;
  int kept = 0;
  bool whole = true;  // the window within both images as the refinement reads them (no margin)
  double all = 0, inside = 0;
  for (int k = 0; k < n; ++k) {
    const long lx = cx + s.oi[k] - img1.x0, ly = cy + s.oj[k] - img1.y0;
    const double u = s.oi[k] + fx, v = s.oj[k] + fy;
    const double qx = ox + A0(0, 0) * u + A0(0, 1) * v, qy = oy + A0(1, 0) * u + A0(1, 1) * v;
    const bool in1 = lx >= 0 && ly >= 0 && lx < img1.width && ly < img1.height;
    const bool in = in1 && qx >= x_lo && qy >= y_lo && qx < x_hi && qy < y_hi;
    whole = whole && in1 && qx >= 1 && qy >= 1 && qx < img2.width - 2 && qy < img2.height - 2;
    if (k < m) {
      const double t = std::exp(-(u * u + v * v) * den);
      all += t;
      inside += in ? t : 0.0;
    }
    if (in) s.ci[kept] = s.oi[k], s.cj[kept] = s.oj[k], s.cidx[kept] = k, ++kept;
  }
  if (kept == n || whole) return n;
  return kept > 0 && inside >= o.edge_share * all ? kept : 0;
}

}  // namespace

double lsm_curvature(const Eigen::Matrix<double, 6, 1>& H) {
  // second derivatives: d2x/du2 = 2 H0, d2x/dudv = H1, d2x/dv2 = 2 H2 (y: H3..H5)
  double s = 0;
  for (int c = 0; c < 2; ++c) {
    const double a = 2 * H(3 * c), b = H(3 * c + 1), d = 2 * H(3 * c + 2);
    s += a * a + 2 * b * b + d * d;
  }
  return std::sqrt(s);
}

LsmResult lsm_refine(const Raster& img1, const Raster& img2, const Eigen::Vector2d& p1, const Eigen::Vector2d& p2,
                     const Eigen::Matrix2d& A0, const LsmOptions& o) {
  LsmResult res;
  res.p2 = p2;
  res.A = A0;
  const int h = o.window / 2, w = 2 * h + 1;
  thread_local Scratch s;
  s.prepare(w);
  const long cx = std::lround(p1.x()), cy = std::lround(p1.y());
  const double fx = cx - p1.x(), fy = cy - p1.y();
  // the window's pixels (n, in order of radius; oi oj their offsets, cidx their indices in s.oi when cut)
  int n = w * w;
  const int* oi = s.oi.data();
  const int* oj = s.oj.data();
  bool cut = false;
  if (o.edge_share > 0) {
    const int kept = cut_window_at_edges(s, img1, img2, cx, cy, fx, fy, p2, A0, o);
    if (kept == 0) {
      res.status = LsmStatus::OutOfImage;
      return res;
    }
    if (kept < n) {
      n = kept, cut = true;
      oi = s.ci.data(), oj = s.cj.data();
    }
  }
  // the number of the window's pixels within `radius` of its centre pixel
  auto within = [&](double radius) {
    const int k = s.within(radius);
    return cut ? static_cast<int>(std::lower_bound(s.cidx.begin(), s.cidx.begin() + n, k) - s.cidx.begin()) : k;
  };
  // template (fixed): image 1's own pixels around p1, no resampling; offsets d from p1 are fractional
  for (int k = 0; k < n; ++k) {
    const long X = cx + oi[k], Y = cy + oj[k];
    const long lx = X - img1.x0, ly = Y - img1.y0;
    if (lx < 0 || ly < 0 || lx >= img1.width || ly >= img1.height) {
      res.status = LsmStatus::OutOfImage;
      return res;
    }
    s.du[k] = oi[k] + fx;
    s.dv[k] = oj[k] + fy;
    s.t[k] = img1.at(lx, ly);
    if (std::isnan(s.t[k])) {
      res.status = LsmStatus::Invalid;
      return res;
    }
  }
  const double mt = sum4(n, [&](int k) { return s.t[k]; }) / n;
  const double st = std::sqrt(sum4(n, [&](int k) { return (s.t[k] - mt) * (s.t[k] - mt); }) / n);
  if (!(st > 1e-6 * (1 + std::abs(mt)))) {
    res.status = LsmStatus::Flat;
    return res;
  }
  for (int k = 0; k < n; ++k) s.t[k] = (s.t[k] - mt) / st;

  // taper of the current stage and the pixels it uses (a prefix of m pixels)
  int m = n;
  double sigma_t = o.taper;
  auto set_taper = [&](double sg) {
    sigma_t = sg;
    const double support = o.quadratic ? o.quadratic_support : o.support;
    m = sg > 0 && support > 0 ? std::min(n, within(support * sg)) : n;
    const double den = sg > 0 ? 1.0 / (2 * sg * sg) : 0.0;
    // the Gaussian is separable: 2 w exponentials instead of one a pixel
    for (int i = -h; i <= h; ++i) {
      s.taper_u[i + h] = sg > 0 ? std::exp(-(i + fx) * (i + fx) * den) : 1.0;
      s.taper_v[i + h] = sg > 0 ? std::exp(-(i + fy) * (i + fy) * den) : 1.0;
    }
    for (int k = 0; k < m; ++k) s.tap[k] = s.taper_u[oi[k] + h] * s.taper_v[oj[k] + h];
  };
  set_taper(o.taper);

  // image 2 scaled once by the initial window's statistics, so that r0 ~ 0 and r1 ~ 1. The first m
  // pixels' gradients are kept: they are the first iteration's (same positions, same operations).
  const double ox = p2.x() - img2.x0, oy = p2.y() - img2.y0;
  for (int k = 0; k < n; ++k) {
    const double u = s.du[k], v = s.dv[k];
    s.qx[k] = ox + A0(0, 0) * u + A0(0, 1) * v;
    s.qy[k] = oy + A0(1, 0) * u + A0(1, 1) * v;
  }
  if (!bicubic_batch<true>(img2, s.qx.data(), s.qy.data(), 0, m, s.g.data(), s.gx.data(), s.gy.data(), o.baseline_code) ||
      !bicubic_batch<false>(img2, s.qx.data(), s.qy.data(), m, n, s.g.data(), s.gx.data(), s.gy.data(), o.baseline_code)) {
    res.status = LsmStatus::OutOfImage;
    return res;
  }
  const double m2 = sum4(n, [&](int k) { return s.g[k]; }) / n;
  const double s2 = std::sqrt(sum4(n, [&](int k) { return (s.g[k] - m2) * (s.g[k] - m2); }) / n);
  if (!(s2 > 1e-6 * (1 + std::abs(m2)))) {
    res.status = LsmStatus::Flat;
    return res;
  }
  const double inv_s2 = 1.0 / s2;
  // pixel k's normalised value, gradient (Grad) and residual from image 2's value and gradient
  auto store = [&](int k, double val, double vx, double vy, double c0, double c1, auto grad) {
    const double g = (val - m2) * inv_s2;
    s.g[k] = g;
    if constexpr (decltype(grad)::value) {
      s.gx[k] = vx * inv_s2;
      s.gy[k] = vy * inv_s2;
    }
    s.r[k] = c0 + c1 * g - s.t[k];
  };
  for (int k = 0; k < m; ++k) store(k, s.g[k], s.gx[k], s.gy[k], 0.0, 1.0, std::true_type());

  // parameters: 0,1 p2; 2..5 A (a11 a12 a21 a22); 6 r0; 7 r1; 8..13 quadratic terms of x, y (u^2, uv, v^2) x qs
  const double qscale = o.taper > 0 ? o.taper : std::max(1, h);
  const double qs = 1.0 / (qscale * qscale);
  // curvature only along the epipolar direction of image 2 (11 parameters) when it is given
  const double en = o.epipolar_dir.norm();
  const bool epi = en > 0;
  const double ex = epi ? o.epipolar_dir.x() / en : 0, ey = epi ? o.epipolar_dir.y() / en : 0;
  const int PQ = epi ? 11 : kMaxP;
  Eigen::Matrix<double, kMaxP, 1> th = Eigen::Matrix<double, kMaxP, 1>::Zero();
  th.head<8>() << p2.x(), p2.y(), A0(0, 0), A0(0, 1), A0(1, 0), A0(1, 1), 0.0, 1.0;
  Eigen::Matrix<double, kMaxP, 1> th_eval = th;  // the model at which the support's pixels were last evaluated
  // image 2 under the model p at pixels first..count - 1, with gradients below `grad_count`
  auto evaluate_model = [&](const Eigen::Matrix<double, kMaxP, 1>& p, int first, int count, int grad_count, auto quad) -> bool {
    const double bx = p(0) - img2.x0, by = p(1) - img2.y0;
    const double a11 = p(2), a12 = p(3), a21 = p(4), a22 = p(5), c0 = p(6), c1 = p(7);
    const int values_from = std::max(first, grad_count);
    for (int k = first; k < count; ++k) {
      const double u = s.du[k], v = s.dv[k];
      double qx = bx + a11 * u + a12 * v, qy = by + a21 * u + a22 * v;
      if constexpr (decltype(quad)::value) {
        const double U = qs * u * u, W = qs * u * v, V = qs * v * v;
        if (epi) {
          const double c = p(8) * U + p(9) * W + p(10) * V;
          qx += ex * c;
          qy += ey * c;
        } else {
          qx = qx + p(8) * U + p(9) * W + p(10) * V;
          qy = qy + p(11) * U + p(12) * W + p(13) * V;
        }
      }
      s.qx[k] = qx;
      s.qy[k] = qy;
    }
    if (!bicubic_batch<true>(img2, s.qx.data(), s.qy.data(), first, grad_count, s.g.data(), s.gx.data(), s.gy.data(), o.baseline_code) ||
        !bicubic_batch<false>(img2, s.qx.data(), s.qy.data(), values_from, count, s.g.data(), s.gx.data(), s.gy.data(), o.baseline_code))
      return false;
    for (int k = first; k < grad_count; ++k) store(k, s.g[k], s.gx[k], s.gy[k], c0, c1, std::true_type());
    for (int k = values_from; k < count; ++k) store(k, s.g[k], 0.0, 0.0, c0, c1, std::false_type());
    return true;
  };
  // the affine model skips the quadratic terms (zero then, so the positions are the same)
  auto evaluate = [&](const Eigen::Matrix<double, kMaxP, 1>& p, int count, int grad_count, int first = 0) -> bool {
    if (p.segment<6>(8).isZero(0)) return evaluate_model(p, first, count, grad_count, std::false_type());  // also the affine stage
    return evaluate_model(p, first, count, grad_count, std::true_type());
  };
  // the six quadratic terms (x: u^2 uv v^2, y: same) of the parameter vector, unscaled by qs
  auto quadratic_terms = [&](const Eigen::Matrix<double, kMaxP, 1>& p) -> Eigen::Matrix<double, 6, 1> {
    Eigen::Matrix<double, 6, 1> H;
    if (epi) H << ex * p(8), ex * p(9), ex * p(10), ey * p(8), ey * p(9), ey * p(10);
    else H = p.segment<6>(8);
    return H;
  };
  Normal<8> n8;
  Normal<kMaxP> n14;
  Normal<11> n11;
  // the sandwich covariance of p2 of the current model (P parameters) at the support's last evaluation
  auto sandwich_cov = [&](int P, double r1) -> Sandwich {
    return P == 8 ? sandwich_cov_support<8>(s, m, r1, qs, ex, ey)
                  : P == 11 ? sandwich_cov_support<11>(s, m, r1, qs, ex, ey) : sandwich_cov_support<kMaxP>(s, m, r1, qs, ex, ey);
  };
  // stages: 0 affine (taper); 1 quadratic (taper); 2 quadratic with the taper chosen from stage 1's curvature
  int stage = 0, P = 8, stage_start = 0;
  bool converged = false, fallback = false;
  int it = 0;
  Eigen::Matrix<double, kMaxP, 1> delta, th_affine = th;
  Eigen::Matrix<double, kMaxP, 1> last = Eigen::Matrix<double, kMaxP, 1>::Zero();  // the last IRLS step, and its shift
  double last_step = 0;
  // The curvature's significance (LsmOptions::measure_curvature): the quadratic model's position differs
  // from the affine one's by d (the affine window's bias where the map curves, plus the noise the
  // curvature terms add). Without curvature d has the covariance Cq - Ca of the two sandwich estimates
  // (nested models, as in Hausman's test), so d' (Cq - Ca)^-1 d, along the epipolar direction when the
  // curvature acts only along it, is chi-square with 1 (else 2) degrees of freedom. Cq - Ca is floored at
  // 5% of Cq (two estimates of nearly equal covariances).
  Eigen::Matrix2d cov_affine = Eigen::Matrix2d::Zero();
  auto curvature_chi2 = [&](const Eigen::Matrix2d& cov_quadratic) {
    const Eigen::Vector2d d = th.head<2>() - th_affine.head<2>();
    const Eigen::Matrix2d D = cov_quadratic - cov_affine;
    if (!D.allFinite()) return std::numeric_limits<double>::quiet_NaN();
    if (epi) {
      const Eigen::Vector2d e(ex, ey);
      const double v = std::max(e.dot(D * e), 0.05 * e.dot(cov_quadratic * e));
      return d.dot(e) * d.dot(e) / v;
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(D);
    const Eigen::Vector2d lam = es.eigenvalues().cwiseMax(0.05 * 0.5 * cov_quadratic.trace());
    const Eigen::Vector2d c = es.eigenvectors().transpose() * d;
    return c(0) * c(0) / lam(0) + c(1) * c(1) / lam(1);
  };
  // the quadratic stages have their own budget beyond the affine stage's max_iterations
  const int cap = o.max_iterations + (o.quadratic ? o.stage_iterations * (o.adaptive ? 2 : 1) : 0);
  thread_local std::vector<double> mask_buf;
  // the fit's mask (LsmOptions::mask_fit_k): its threshold from the residuals of the first L1 iteration of
  // each stage, kept for the stage (the median's selection took a fifth of the refinement's time when done
  // on every iteration; by then the fit is near its solution, and the accuracy on tp-synth truth was the
  // same: default scene, triplets' views 2+3 median / p90 0.0288 / 0.0817 px on every iteration, 0.0286 /
  // 0.0819 once per stage)
  double fit_thr = std::numeric_limits<double>::infinity();
  bool fit_thr_due = true;  // at the stage's first L1 iteration
  for (; it < cap; ++it) {
    if (stage == 0 && it >= o.max_iterations) break;
    if (stage > 0 && it - stage_start >= o.stage_iterations) {
      fallback = true;  // the quadratic stages did not settle: keep the affine solution
      break;
    }
    // (the first iteration's image 2 is the normalisation's)
    if (it > 0 && !evaluate(th, m, m)) {
      res.status = LsmStatus::OutOfImage;
      return res;
    }
    th_eval = th;
    // IRLS weights: plain least squares for the first two iterations, then L1
    if (o.l1 && it >= 2)
      for (int k = 0; k < m; ++k) s.wt[k] = s.tap[k] / std::max(std::abs(s.r[k]), o.eps);
    else
      for (int k = 0; k < m; ++k) s.wt[k] = s.tap[k];
    if (o.mask_fit_k > 0 && it >= 2) {
      if (fit_thr_due) {
        fit_thr = mask_threshold(s, m, o.mask_fit_k, mask_buf);
        fit_thr_due = false;
      }
      mask_residuals(s, m, fit_thr);
    }
    bool ok;
    if (P == 8) {
      accumulate8_fast(s, m, th(7), n8);
      ok = gn_step<8>(n8, delta);
    } else if (P == 11) {
      accumulate<11>(s, m, th(7), qs, n11, true, ex, ey);
      ok = gn_step<11>(n11, delta);
    } else {
      accumulate<kMaxP>(s, m, th(7), qs, n14, true);
      ok = gn_step<kMaxP>(n14, delta);
    }
    if (!ok) {
      if (stage > 0) {
        fallback = true;
        break;
      }
      res.status = LsmStatus::Diverged;
      return res;
    }
    // damp wild steps of the shift
    double step = delta.head<2>().norm();
    if (step > 1.0) delta *= 1.0 / step;
    // Over-relaxed IRLS: in the L1 phase, where the image fits a point only a few pixels support
    // (buildings, edges), the L1 optimum can lie tenths of a pixel from the least-squares one and the
    // IRLS steps creep towards it in the same direction, each ~0.9-0.97 of the last. A step along the
    // last one (cosine > 0.9) shrinking by rho is stretched by 1 / (1 - rho) (the sum of the steps to
    // come), at most 2: a step up to twice the IRLS one never raises the reweighted quadratic the IRLS
    // step minimises, so the fixed point and the acceptance tests are the same, only reached in fewer
    // iterations. Convergence is still tested on the IRLS step itself.
    const Eigen::Matrix<double, kMaxP, 1> irls = delta;
    if (o.l1 && it >= 3 && it - 1 >= stage_start && last_step > 0) {
      const double cosine = delta.head<2>().dot(last.head<2>()) / (step * last_step), rho = step / last_step;
      if (cosine > 0.9 && rho < 1) delta *= std::min(2.0, 1.0 / (1.0 - rho));
    }
    last = irls;
    last_step = step;
    th += delta;
    if ((th.head<2>() - p2).norm() > 3 * o.max_shift + 2) {
      if (stage > 0) {
        fallback = true;
        break;
      }
      res.status = LsmStatus::Diverged;
      return res;
    }
    // With L1, the affine stage may stop after its first L1 iteration, whose step is below the tolerance
    // in 54% of the 10000² pair's windows: waiting for a second one (as before) took 4.38 iterations on
    // average instead of 3.84, with no gain in accuracy (synthetic default scene 0.0666 / 0.1830 ->
    // 0.0667 / 0.1829 px, relief scene unchanged; Marseille ML fit 0.0987 px either way). The quadratic
    // stages, which start from the affine solution, keep the two.
    if (step < (stage == 0 ? o.tolerance : o.stage_tolerance) && (!o.l1 || it >= (stage == 0 ? 2 : 3))) {
      if (stage == 0 && o.quadratic) {
        if (o.measure_curvature) cov_affine = sandwich_cov(8, th_eval(7)).cov();
        stage = 1;
        stage_start = it + 1;
        fit_thr_due = true;
        P = PQ;
        th_affine = th;
        continue;
      }
      if (stage == 1 && o.measure_curvature) res.curvature_chi2 = curvature_chi2(sandwich_cov(P, th_eval(7)).cov());
      if (stage == 1 && o.adaptive) {
        stage = 2;
        const Eigen::Matrix<double, 6, 1> H = quadratic_terms(th) * qs;
        const double c = lsm_curvature(H);
        double sg = c > 0 ? o.taper * std::pow(c / o.curvature_ref, -0.25) : o.taper_max;
        sg = std::clamp(sg, o.taper_min, o.taper_max);
        if (std::abs(sg - sigma_t) > 0.25) {
          set_taper(sg);
          stage_start = it + 1;
          fit_thr_due = true;
          continue;
        }
      }
      converged = true;
      ++it;
      break;
    }
  }
  if (!converged && stage > 0) fallback = true;  // the iteration cap came in a quadratic stage
  if (fallback) {
    // back to the converged affine solution, with its taper and its L1 weights
    th = th_affine;
    P = 8;
    set_taper(o.taper);
    if (!evaluate(th, m, m)) {
      res.status = LsmStatus::OutOfImage;
      return res;
    }
    for (int k = 0; k < m; ++k) s.wt[k] = o.l1 ? s.tap[k] / std::max(std::abs(s.r[k]), o.eps) : s.tap[k];
    if (o.mask_fit_k > 0) mask_residuals(s, m, mask_threshold(s, m, o.mask_fit_k, mask_buf));
    converged = true;
  }
  res.iterations = it;
  res.quadratic = P > 8;
  res.taper = sigma_t;
  res.p2 = th.head<2>();
  res.A << th(2), th(3), th(4), th(5);
  res.r0 = th(6);
  res.r1 = th(7);
  res.H = quadratic_terms(th) * qs;
  if (!converged) {
    res.status = LsmStatus::NotConverged;
    return res;
  }
  // the fit's precision and correlation are those of the last iteration's state, less than the tolerance
  // from the solution: its normal matrix, its residuals, and its model at the pixels outside the support
  // (values only). Against those at the solution itself, sigma on the Marseille pair 1-2 moves 0.3% on
  // average and 4.4% at most (the spread of sigma0's own estimate from ~200 residuals), the correlation
  // 0.022 at most: an iteration's worth of gradients, a normal matrix and the support's values less, 12% of
  // the refinement. After a fallback the affine model's state is built afresh at its solution.
  const bool last_state = !fallback;
  if (!(last_state ? evaluate(th_eval, n, 0, m) : evaluate(th, n, m))) {
    res.status = LsmStatus::OutOfImage;
    return res;
  }
  {
    const double sum_wr2 = sum4(m, [&](int k) { return s.wt[k] * s.r[k] * s.r[k]; });
    double var;
    if (last_state) {
      var = P == 8 ? var_p2<8>(n8) : P == 11 ? var_p2<11>(n11) : var_p2<kMaxP>(n14);
    } else if (P == 8) {
      accumulate<8>(s, m, th(7), qs, n8, false);
      var = var_p2<8>(n8);
    } else if (P == 11) {
      accumulate<11>(s, m, th(7), qs, n11, false, ex, ey);
      var = var_p2<11>(n11);
    } else {
      accumulate<kMaxP>(s, m, th(7), qs, n14, false);
      var = var_p2<kMaxP>(n14);
    }
    // degrees of freedom: the pixels that kept a weight (all of the support without a mask)
    int kept = 0;
    for (int k = 0; k < m; ++k) kept += s.wt[k] > 0;
    var *= sum_wr2 / std::max(1, kept - P);
    if (o.sigma_sandwich) var = sandwich_cov(P, last_state ? th_eval(7) : th(7)).var();
    // a singular final matrix gives no precision: refused as imprecise, not passed as sigma 0
    res.sigma_fit = std::isfinite(var) ? std::sqrt(std::max(var, 0.0)) : std::numeric_limits<double>::infinity();
    res.sigma = std::hypot(o.sigma_scale * (res.quadratic ? o.quadratic_sigma_ratio : 1.0) * res.sigma_fit, o.sigma_floor);
  }
  {
    const double mg = sum4(n, [&](int k) { return s.g[k]; }) / n;
    const double sgg = sum4(n, [&](int k) { return (s.g[k] - mg) * (s.g[k] - mg); });
    const double stg = sum4(n, [&](int k) { return (s.g[k] - mg) * s.t[k]; });
    const double stt = sum4(n, [&](int k) { return s.t[k] * s.t[k]; });
    res.corr = sgg > 0 ? stg / std::sqrt(sgg * stt) : 0;
    res.corr_inliers = res.corr;
    res.inlier_share = 1;
    // the residual mask's threshold from the support's final residuals (infinite without one)
    const double mask_thr = mask_threshold(s, m, o.mask_k, mask_buf);
    if (std::isfinite(mask_thr)) {
      // the same over the pixels within the mask's threshold (the whole window's residuals at the model
      // the correlation is measured at)
      double c = 0, a = 0, b = 0;
      for (int k = 0; k < n; ++k)
        if (std::abs(s.r[k]) <= mask_thr) c += 1, a += s.g[k], b += s.t[k];
      res.inlier_share = c / n;
      if (c > 2) {
        a /= c, b /= c;
        double gg = 0, tg = 0, tt = 0;
        for (int k = 0; k < n; ++k)
          if (std::abs(s.r[k]) <= mask_thr) {
            const double dg = s.g[k] - a, dt = s.t[k] - b;
            gg += dg * dg, tg += dg * dt, tt += dt * dt;
          }
        res.corr_inliers = gg > 0 && tt > 0 ? tg / std::sqrt(gg * tt) : 0;
      } else {
        res.corr_inliers = 0;
      }
    }
  }
  double det = res.A.determinant(), det0 = A0.determinant();
  if (!(det > 0) || !(det0 > 0) || det / det0 > 4 || det / det0 < 0.25) {
    res.status = LsmStatus::Diverged;
    return res;
  }
  if ((res.p2 - p2).norm() > o.max_shift) {
    res.status = LsmStatus::Drifted;
    return res;
  }
  if (!(res.sigma <= o.max_sigma)) {
    res.status = LsmStatus::Imprecise;
    return res;
  }
  if (res.corr_inliers < o.min_corr || res.inlier_share < o.min_inliers) {
    res.status = LsmStatus::LowCorrelation;
    return res;
  }
  res.status = LsmStatus::Ok;
  return res;
}

}  // namespace tpkit
