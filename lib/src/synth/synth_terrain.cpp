// Terrain height field of tp-synth: bicubic B-spline over fractal control heights (synth_terrain.hpp).
#include "tpkit/synth/synth_terrain.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "tpkit/core/cpu_dispatch.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/synth/synth_noise.hpp"

namespace tpkit {

using synth::hash;
using synth::uniform;
using synth::value_noise;

namespace {

// Cubic B-spline weights at fraction t in [0, 1] and their derivatives.
inline void bspline(double t, double w[4], double dw[4]) {
  const double t2 = t * t, t3 = t2 * t, s = 1 - t;
  w[0] = s * s * s / 6;
  w[1] = (3 * t3 - 6 * t2 + 4) / 6;
  w[2] = (-3 * t3 + 3 * t2 + 3 * t + 1) / 6;
  w[3] = t3 / 6;
  if (dw) {
    dw[0] = -s * s / 2;
    dw[1] = (3 * t2 - 4 * t) / 2;
    dw[2] = (-3 * t2 + 2 * t + 1) / 2;
    dw[3] = t2 / 2;
  }
}

// The renderer's evaluation of the surface and its gradient at (u, v) grid units, clamped as eval() clamps,
// from the power-basis polynomial of the cell (SynthTerrain::Patch): the same function as eval() but not bit
// for bit (~1e-16 relative), so that refine() (only the renderer's Newton at 1 cm steps) may use it while
// the exact casts, the truth, keep eval().
typedef double v2d __attribute__((vector_size(16)));
// Cubic B-spline control values p0..p3 at knots -1..2 -> power-basis coefficients q0..q3 of t in [0, 1].
inline void bspline_power(const double p[4], double q[4]) {
  q[0] = (p[0] + 4 * p[1] + p[2]) * (1.0 / 6);
  q[1] = (p[2] - p[0]) * 0.5;
  q[2] = (p[0] - 2 * p[1] + p[2]) * 0.5;
  q[3] = (3 * (p[1] - p[2]) + p[3] - p[0]) * (1.0 / 6);
}
// The power-basis coefficients of cell (ku, kv) (out of line: a cell serves ~8 Newton steps).
[[gnu::noinline]] TPKIT_HOT void fill_patch(const float* c, long nx, long ku, long kv, SynthTerrain::Patch& P) {
  // rows (knots v) to the power basis in s, then each power of s to the power basis in r
  double rows[4][4];
  for (int b = 0; b < 4; ++b) {
    const float* p = c + (kv - 1 + b) * nx + (ku - 1);
    const double pd[4] = {p[0], p[1], p[2], p[3]};
    bspline_power(pd, rows[b]);
  }
  for (int k = 0; k < 4; ++k) {
    const double col[4] = {rows[0][k], rows[1][k], rows[2][k], rows[3][k]};
    bspline_power(col, P.c[k]);
  }
  P.ku = ku;
  P.kv = kv;
}
// near: another ray's patch (or nullptr), copied where it is the cell's (the four rows of a renderer's group
// are 0.25 px apart, mostly in one cell: a copy instead of filling).
[[gnu::always_inline]] inline double eval_patch(const float* c, long nx, long ny, double u, double v, SynthTerrain::Patch& P,
                                                const SynthTerrain::Patch* near, double& gu, double& gv) {
  u = std::min(std::max(1.0, u), static_cast<double>(nx - 2));
  v = std::min(std::max(1.0, v), static_cast<double>(ny - 2));
  const long ku = std::min(static_cast<long>(u), nx - 3), kv = std::min(static_cast<long>(v), ny - 3);
  if (ku != P.ku || kv != P.kv) {
    if (near && near->ku == ku && near->kv == kv)
      P = *near;
    else
      fill_patch(c, nx, ku, kv, P);
  }
  const double s = u - static_cast<double>(ku), r = v - static_cast<double>(kv);
  // Horner in r for every power of s, the lanes holding r^0, r^1 and r^2, r^3 coefficients
  v2d col[4][2];
  for (int k = 0; k < 4; ++k) {
    col[k][0] = v2d{P.c[k][0], P.c[k][1]};
    col[k][1] = v2d{P.c[k][2], P.c[k][3]};
  }
  // h(s) coefficients of r^j: lanes (j = 0, 1), (j = 2, 3)
  const v2d h01 = ((col[3][0] * s + col[2][0]) * s + col[1][0]) * s + col[0][0];
  const v2d h23 = ((col[3][1] * s + col[2][1]) * s + col[1][1]) * s + col[0][1];
  const v2d d01 = (3 * col[3][0] * s + 2 * col[2][0]) * s + col[1][0];
  const v2d d23 = (3 * col[3][1] * s + 2 * col[2][1]) * s + col[1][1];
  gu = ((d23[1] * r + d23[0]) * r + d01[1]) * r + d01[0];
  gv = (3 * h23[1] * r + 2 * h23[0]) * r + h01[1];
  return ((h23[1] * r + h23[0]) * r + h01[1]) * r + h01[0];
}

}  // namespace

SynthTerrain::SynthTerrain(uint64_t seed, double scene, double relief, double spacing, double x0, double y0,
                           double x1, double y1)
    : h_(spacing) {
  if (!(spacing > 0) || !(scene > 0) || !(x1 > x0) || !(y1 > y0)) throw NumericalError("synth terrain: bad extent");
  // Control point k sits at grid coordinate k; the surface is defined for u in [1, n - 2]: one extra ring.
  gx0_ = std::floor(x0 / h_ - 2) * h_;
  gy0_ = std::floor(y0 / h_ - 2) * h_;
  nx_ = static_cast<long>(std::ceil((x1 - gx0_) / h_)) + 3;
  ny_ = static_cast<long>(std::ceil((y1 - gy0_) / h_)) + 3;
  c_.assign(static_cast<size_t>(nx_) * ny_, 0.f);

  const uint64_t ts = hash(seed, 0x7e77a1);
  // Octaves of value noise: wavelength from S/1.5 down to 4 control spacings, persistence 0.5.
  struct Octave { double lambda, amp, ox, oy; uint64_t seed; };
  std::vector<Octave> octaves;
  double lambda = scene / 1.5, amp = 1.0;
  for (int o = 0; o < 16 && (o < 2 || lambda >= 4 * h_); ++o) {
    octaves.push_back({lambda, amp, 1000 * uniform(ts, o, 1), 1000 * uniform(ts, o, 2), hash(ts, o, 3)});
    lambda /= 2;
    amp *= 0.5;
  }
  // A few large hills (+) and valleys (-): Gaussian bumps.
  struct Hill { double x, y, s, a; };
  std::vector<Hill> hills;
  const int nh = 3 + static_cast<int>(hash(ts, 99) % 4);
  for (int k = 0; k < nh; ++k) {
    const double sgn = uniform(ts, 100, k, 4) < 0.6 ? 1 : -1;
    hills.push_back({scene * (-0.1 + 1.2 * uniform(ts, 100, k, 0)), scene * (-0.1 + 1.2 * uniform(ts, 100, k, 1)),
                     scene * (0.12 + 0.18 * uniform(ts, 100, k, 2)), sgn * (0.6 + 0.8 * uniform(ts, 100, k, 3))});
  }
  for (long j = 0; j < ny_; ++j) {
    const double Y = gy0_ + j * h_;
    for (long i = 0; i < nx_; ++i) {
      const double X = gx0_ + i * h_;
      double z = 0;
      for (const auto& o : octaves) z += o.amp * value_noise(o.seed, X / o.lambda + o.ox, Y / o.lambda + o.oy);
      for (const auto& hl : hills) {
        const double dx = X - hl.x, dy = Y - hl.y;
        z += hl.a * std::exp(-(dx * dx + dy * dy) / (2 * hl.s * hl.s));
      }
      c_[static_cast<size_t>(j) * nx_ + i] = static_cast<float>(z);
    }
  }
  // Range of the surface over the scene: knots, then a dense local search around the extremes.
  auto range = [&](double& lo, double& hi) {
    lo = std::numeric_limits<double>::infinity();
    hi = -lo;
    double xlo = 0, ylo = 0, xhi = 0, yhi = 0;
    const long n = static_cast<long>(std::ceil(scene / h_));
    for (long j = 0; j <= n; ++j)
      for (long i = 0; i <= n; ++i) {
        const double X = std::min(scene, i * h_), Y = std::min(scene, j * h_);
        const double z = height(X, Y);
        if (z < lo) { lo = z; xlo = X; ylo = Y; }
        if (z > hi) { hi = z; xhi = X; yhi = Y; }
      }
    for (int pass = 0; pass < 2; ++pass) {
      const double cx = pass ? xhi : xlo, cy = pass ? yhi : ylo;
      for (int b = -16; b <= 16; ++b)
        for (int a = -16; a <= 16; ++a) {
          const double X = std::clamp(cx + a * h_ / 16, 0.0, scene), Y = std::clamp(cy + b * h_ / 16, 0.0, scene);
          const double z = height(X, Y);
          lo = std::min(lo, z);
          hi = std::max(hi, z);
        }
    }
  };
  // Provisional bounds so that height() works during the range search.
  cmax_.clear();
  double lo, hi;
  range(lo, hi);
  const double mid = 0.5 * (lo + hi);
  const double scale = (hi - lo) > 0 ? relief / (hi - lo) : 0.0;
  for (auto& v : c_) {
    // Outside the scene the fractal goes on; clamping keeps every height within +-relief.
    const double z = std::clamp((v - mid) * scale, -relief, relief);
    v = static_cast<float>(z);
  }
  zmin_ = *std::min_element(c_.begin(), c_.end());
  zmax_ = *std::max_element(c_.begin(), c_.end());
  // Per-cell bound: max over the 4x4 control heights (convex hull property).
  const long cx = nx_ - 3, cy = ny_ - 3;
  std::vector<float> rowmax(static_cast<size_t>(cx) * ny_);
  for (long j = 0; j < ny_; ++j)
    for (long i = 0; i < cx; ++i) {
      const float* p = &c_[static_cast<size_t>(j) * nx_ + i];
      rowmax[static_cast<size_t>(j) * cx + i] = std::max(std::max(p[0], p[1]), std::max(p[2], p[3]));
    }
  cmax_.resize(static_cast<size_t>(cx) * cy);
  cslope_.resize(static_cast<size_t>(cx) * cy);
  for (long j = 0; j < cy; ++j)
    for (long i = 0; i < cx; ++i) {
      float m = rowmax[static_cast<size_t>(j) * cx + i];
      for (int b = 1; b < 4; ++b) m = std::max(m, rowmax[static_cast<size_t>(j + b) * cx + i]);
      cmax_[static_cast<size_t>(j) * cx + i] = m;
      // dh/du is a quadratic B-spline of the u-differences of the control heights (likewise v): its
      // magnitude is bounded by their largest magnitude.
      double gu = 0, gv = 0;
      for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
          const float* p = &c_[static_cast<size_t>(j + b) * nx_ + i + a];
          if (a < 3) gu = std::max(gu, std::abs(static_cast<double>(p[1]) - p[0]));
          if (b < 3) gv = std::max(gv, std::abs(static_cast<double>(p[nx_]) - p[0]));
        }
      cslope_[static_cast<size_t>(j) * cx + i] = static_cast<float>(std::hypot(gu, gv) / h_ * (1 + 1e-6) + 1e-9);
    }
  slope_max_ = *std::max_element(cslope_.begin(), cslope_.end());
}

// Inline: the exact casts (intersect) evaluate the height through it at every step.
[[gnu::always_inline]] inline double SynthTerrain::eval(double u, double v, double* du, double* dv) const {
  // std::max first: a nan position (a diverged Newton start) becomes the grid's edge instead of reaching
  // the integer conversion below, which it would overflow
  u = std::min(std::max(1.0, u), static_cast<double>(nx_ - 2));
  v = std::min(std::max(1.0, v), static_cast<double>(ny_ - 2));
  long ku = std::min(static_cast<long>(u), nx_ - 3), kv = std::min(static_cast<long>(v), ny_ - 3);
  double wu[4], wv[4], dwu[4], dwv[4];
  const bool grad = du != nullptr;
  bspline(u - ku, wu, grad ? dwu : nullptr);
  bspline(v - kv, wv, grad ? dwv : nullptr);
  double z = 0, gu = 0, gv = 0;
  for (int b = 0; b < 4; ++b) {
    const float* p = &c_[static_cast<size_t>(kv - 1 + b) * nx_ + (ku - 1)];
    const double r = wu[0] * p[0] + wu[1] * p[1] + wu[2] * p[2] + wu[3] * p[3];
    z += wv[b] * r;
    if (grad) {
      gu += wv[b] * (dwu[0] * p[0] + dwu[1] * p[1] + dwu[2] * p[2] + dwu[3] * p[3]);
      gv += dwv[b] * r;
    }
  }
  if (grad) {
    *du = gu;
    *dv = gv;
  }
  return z;
}

double SynthTerrain::height(double X, double Y) const {
  return eval((X - gx0_) / h_, (Y - gy0_) / h_, nullptr, nullptr);
}

double SynthTerrain::height(double X, double Y, Eigen::Vector2d* grad) const {
  const double u = (X - gx0_) / h_, v = (Y - gy0_) / h_;
  double gu = 0, gv = 0;
  const double z = eval(u, v, &gu, &gv);
  // Clamped outside the grid: the gradient there is that of the clamped (constant) direction.
  const bool inu = u > 1 && u < nx_ - 2, inv = v > 1 && v < ny_ - 2;
  if (grad) *grad = Eigen::Vector2d(inu ? gu / h_ : 0.0, inv ? gv / h_ : 0.0);
  return z;
}

double SynthTerrain::refine(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t, double tol, Eigen::Vector2d* grad,
                            Patch* patch) const {
  Patch own;
  Eigen::Vector2d g;
  refine_lanes(1, &o, &d, &t, tol, &g, patch ? patch : &own);
  if (grad && !std::isnan(t)) *grad = g;
  return t;
}

TPKIT_HOT void SynthTerrain::refine_lanes(int n, const Eigen::Vector3d* o, const Eigen::Vector3d* d, double* t, double tol,
                                Eigen::Vector2d* grad, Patch* patch) const {
  // height(X, Y, &g) written out, multiplying by 1 / h instead of dividing, with eval_patch (this loop is the
  // renderer's inner loop: one call a node; a last-bit difference from height() is immaterial at its 1 cm
  // tolerance)
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double ih = 1 / h_, umax = static_cast<double>(nx_ - 2), vmax = static_cast<double>(ny_ - 2);
  bool open[kLanes];
  int left = n;
  for (int k = 0; k < kLanes; ++k) open[k] = k < n;
  for (int it = 0; it < 8 && left > 0; ++it)
    for (int k = 0; k < kLanes; ++k) {  // one Newton step of every open ray
      if (!open[k]) continue;
      double& tk = t[k];
      const double ox = o[k].x(), oy = o[k].y(), oz = o[k].z(), dx = d[k].x(), dy = d[k].y(), dz = d[k].z();
      bool done = !std::isfinite(tk);  // diverged: the caller casts exactly
      if (done) {
        tk = nan;
      } else {
        const double u = (ox + tk * dx - gx0_) * ih, v = (oy + tk * dy - gy0_) * ih;
        double gu = 0, gv = 0;
        const double z = eval_patch(c_.data(), nx_, ny_, u, v, patch[k], k > 0 ? &patch[k - 1] : nullptr, gu, gv);
        const double gx = u > 1 && u < umax ? gu * ih : 0.0, gy = v > 1 && v < vmax ? gv * ih : 0.0;
        const double f = oz + tk * dz - z;
        const double fp = dz - (gx * dx + gy * dy);
        if (!(fp < -1e-9)) {
          tk = nan;
          done = true;
        } else {
          const double dt = f / fp;
          tk -= dt;
          if (std::abs(dt) < tol + 1e-15 * std::abs(tk)) {
            grad[k] = Eigen::Vector2d(gx, gy);
            done = true;
          }
        }
      }
      if (done) {
        open[k] = false;
        --left;
      }
    }
  for (int k = 0; k < n; ++k)
    if (open[k]) t[k] = nan;  // no convergence in 8 steps
}

TPKIT_HOT std::optional<double> SynthTerrain::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tol_t) const {
  if (!(d.z() < 0)) return std::nullopt;
  // ray height above the terrain: height() written out, with eval inline
  auto f = [&](double t) { return o.z() + t * d.z() - eval((o.x() + t * d.x() - gx0_) / h_, (o.y() + t * d.y() - gy0_) / h_, nullptr, nullptr); };
  const double t0 = std::max(0.0, (o.z() - zmax_) / -d.z());
  const double t1 = (o.z() - zmin_) / -d.z();
  if (!(t1 >= t0)) return std::nullopt;
  // Bracketed refinement (Illinois false position) of a sign change f(a) > 0 >= f(b).
  auto solve = [&](double a, double b, double fa, double fb) {
    const double tol = tol_t + 1e-15 * std::abs(b);
    int side = 0;
    for (int it = 0; it < 200 && b - a > tol; ++it) {
      double c = (a * fb - b * fa) / (fb - fa);
      if (!(c > a && c < b) || it % 8 == 7) c = 0.5 * (a + b);
      const double fc = f(c);
      if (fc > 0) {
        a = c;
        fa = fc;
        if (side == 1) fb *= 0.5;
        side = 1;
      } else {
        b = c;
        fb = fc;
        if (fc == 0) return c;
        if (side == -1) fa *= 0.5;
        side = -1;
      }
    }
    return std::abs(fa) < std::abs(fb) ? a : b;
  };
  const double u0 = (o.x() + t0 * d.x() - gx0_) / h_, v0 = (o.y() + t0 * d.y() - gy0_) / h_;
  const double du = d.x() / h_, dv = d.y() / h_;
  // |(du, dv)| and |(d.x, d.y)| by std::hypot (slow: 2 % of a whole tp-synth run), kept per thread for the
  // last direction and spacing: an affine view casts every ray along one direction
  struct Speeds {
    double dx = 0, dy = 0, h = 0, hspeed = 0, dxy = 0;
    bool valid = false;
  };
  thread_local Speeds sp;
  if (!sp.valid || sp.dx != d.x() || sp.dy != d.y() || sp.h != h_)
    sp = {d.x(), d.y(), h_, std::hypot(du, dv), std::hypot(d.x(), d.y()), true};
  const double hspeed = sp.hspeed;  // grid units per unit t
  long ku = static_cast<long>(std::floor(u0)), kv = static_cast<long>(std::floor(v0));
  const double inf = std::numeric_limits<double>::infinity();
  const int su = du > 0 ? 1 : -1, sv = dv > 0 ? 1 : -1;
  double tnu = du > 0 ? t0 + (ku + 1 - u0) / du : (du < 0 ? t0 + (ku - u0) / du : inf);
  double tnv = dv > 0 ? t0 + (kv + 1 - v0) / dv : (dv < 0 ? t0 + (kv - v0) / dv : inf);
  const double tdu = du != 0 ? 1 / std::abs(du) : inf, tdv = dv != 0 ? 1 / std::abs(dv) : inf;
  const long cxn = nx_ - 3, cyn = ny_ - 3;
  const double dxy = sp.dxy;
  // First root in [a, b] given f(a) > 0 and f(b) > 0, where |f'| <= K: a dip below zero needs
  // (f(a) + f(b)) / 2 < K (b - a) / 2; otherwise split. (A lambda taking itself: a std::function here cost
  // a heap allocation per cast.)
  auto dip_rec = [&](auto& self, double a, double b, double fa, double fb, double K, int depth) -> std::optional<double> {
    if (fa + fb > K * (b - a) || depth > 40 || b - a < 1e-12 * (1 + std::abs(b))) return std::nullopt;
    const double m = 0.5 * (a + b), fm = f(m);
    if (fm <= 0) return solve(a, m, fa, fm);
    if (auto r = self(self, a, m, fa, fm, K, depth + 1)) return r;
    return self(self, m, b, fm, fb, K, depth + 1);
  };
  auto dip = [&](double a, double b, double fa, double fb, double K, int depth) { return dip_rec(dip_rec, a, b, fa, fb, K, depth); };
  double ta = t0;
  double fprev = f(t0), tprev = t0;
  if (fprev <= 0) return t0;
  for (long guard = 0; guard < 100000000; ++guard) {
    const double tb = std::min(std::min(tnu, tnv), t1);
    const long ci = ku - 1, cj = kv - 1;
    const bool in = ci >= 0 && ci < cxn && cj >= 0 && cj < cyn;
    const double bound = in ? cmax_[static_cast<size_t>(cj) * cxn + ci] : zmax_;
    // Outside the grid the height is clamped: its slope is bounded by that of the border cells, which
    // the global bound covers.
    const double K = -d.z() + (in ? cslope_[static_cast<size_t>(cj) * cxn + ci] : slope_max_) * dxy;
    if (o.z() + tb * d.z() <= bound + 1e-9 * (1 + std::abs(bound))) {
      double a = std::max(ta, (o.z() - bound) / -d.z());
      if (a != tprev) {
        fprev = f(a);
        tprev = a;
        if (fprev <= 0) return a;  // cannot happen for a true bound; kept for safety
      }
      const int n = 1 + static_cast<int>(std::ceil((tb - a) * hspeed * 2));  // half-cell samples
      for (int s = 1; s <= n; ++s) {
        const double b = s == n ? tb : a + (tb - a) * s / n;
        const double fb = f(b);
        if (fb <= 0) return solve(a, b, fprev, fb);
        if (auto r = dip(a, b, fprev, fb, K, 0)) return r;
        a = b;
        fprev = fb;
        tprev = b;
      }
    }
    if (tb >= t1) break;
    ta = tb;
    if (tnu < tnv) {
      ku += su;
      tnu += tdu;
    } else {
      kv += sv;
      tnv += tdv;
    }
  }
  return std::nullopt;
}

}  // namespace tpkit
