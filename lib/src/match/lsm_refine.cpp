#include "tpkit/lsm_refine.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <cmath>
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
  }
  return "?";
}

namespace {
inline void keys(double t, double w[4], double dw[4]) {
  // weights of samples at offsets -1, 0, 1, 2 for fractional position t in [0, 1), and d/dt
  const double a = -0.5;
  auto k = [a](double s) {
    s = std::abs(s);
    if (s < 1) return ((a + 2) * s - (a + 3)) * s * s + 1;
    if (s < 2) return ((a * s - 5 * a) * s + 8 * a) * s - 4 * a;
    return 0.0;
  };
  auto dk = [a](double s) {  // derivative of k(s) with respect to s
    double as = std::abs(s), sg = s < 0 ? -1.0 : 1.0;
    if (as < 1) return sg * (3 * (a + 2) * as * as - 2 * (a + 3) * as);
    if (as < 2) return sg * (3 * a * as * as - 10 * a * as + 8 * a);
    return 0.0;
  };
  for (int i = 0; i < 4; ++i) {
    double s = t - (i - 1);  // distance from sample i-1
    w[i] = k(s);
    dw[i] = dk(s);
  }
}
}  // namespace

bool bicubic(const Raster& r, double x, double y, double& value, double* gx, double* gy) {
  double lx = x - r.x0, ly = y - r.y0;
  long ix = static_cast<long>(std::floor(lx)), iy = static_cast<long>(std::floor(ly));
  if (ix < 1 || iy < 1 || ix + 2 >= r.width || iy + 2 >= r.height) return false;
  double wx[4], dwx[4], wy[4], dwy[4];
  keys(lx - ix, wx, dwx);
  keys(ly - iy, wy, dwy);
  double v = 0, vx = 0, vy = 0;
  for (int j = 0; j < 4; ++j) {
    const float* row = r.data.data() + static_cast<size_t>(iy - 1 + j) * r.width + (ix - 1);
    double s = 0, sx = 0;
    for (int i = 0; i < 4; ++i) {
      s += wx[i] * row[i];
      sx += dwx[i] * row[i];
    }
    v += wy[j] * s;
    vx += wy[j] * sx;
    vy += dwy[j] * s;
  }
  if (std::isnan(v)) return false;
  value = v;
  if (gx) *gx = vx;
  if (gy) *gy = vy;
  return true;
}

LsmResult lsm_refine(const Raster& img1, const Raster& img2, const Eigen::Vector2d& p1, const Eigen::Vector2d& p2,
                     const Eigen::Matrix2d& A0, const LsmOptions& o) {
  LsmResult res;
  res.p2 = p2;
  res.A = A0;
  const int h = o.window / 2, w = 2 * h + 1, n = w * w;
  // template (fixed): image 1's own pixels around p1, no resampling; offsets d from p1 are fractional
  std::vector<double> t(n), du(n), dv(n);
  double mt = 0;
  const long cx = std::lround(p1.x()), cy = std::lround(p1.y());
  for (int j = 0, k = 0; j < w; ++j)
    for (int i = 0; i < w; ++i, ++k) {
      long X = cx + i - h, Y = cy + j - h;
      du[k] = X - p1.x();
      dv[k] = Y - p1.y();
      long lx = X - img1.x0, ly = Y - img1.y0;
      if (lx < 0 || ly < 0 || lx >= img1.width || ly >= img1.height) {
        res.status = LsmStatus::OutOfImage;
        return res;
      }
      t[k] = img1.at(lx, ly);
      if (std::isnan(t[k])) {
        res.status = LsmStatus::Invalid;
        return res;
      }
      mt += t[k];
    }
  mt /= n;
  double st = 0;
  for (double v : t) st += (v - mt) * (v - mt);
  st = std::sqrt(st / n);
  if (!(st > 1e-6 * (1 + std::abs(mt)))) {
    res.status = LsmStatus::Flat;
    return res;
  }
  for (double& v : t) v = (v - mt) / st;

  // image 2 scaled once by the initial window's statistics, so that r0 ~ 0 and r1 ~ 1
  double m2 = 0, s2 = 0;
  {
    std::vector<double> g(n);
    for (int k = 0; k < n; ++k) {
      Eigen::Vector2d q = p2 + A0 * Eigen::Vector2d(du[k], dv[k]);
      if (!bicubic(img2, q.x(), q.y(), g[k])) {
        res.status = LsmStatus::OutOfImage;
        return res;
      }
      m2 += g[k];
    }
    m2 /= n;
    for (double v : g) s2 += (v - m2) * (v - m2);
    s2 = std::sqrt(s2 / n);
    if (!(s2 > 1e-6 * (1 + std::abs(m2)))) {
      res.status = LsmStatus::Flat;
      return res;
    }
  }
  const double inv_s2 = 1.0 / s2;

  // parameters: 0,1 p2; 2..5 A (a11 a12 a21 a22); 6 r0; 7 r1
  Eigen::Matrix<double, 8, 1> th;
  th << p2.x(), p2.y(), A0(0, 0), A0(0, 1), A0(1, 0), A0(1, 1), 0.0, 1.0;
  Eigen::Matrix<double, 8, 8> N;
  Eigen::Matrix<double, 8, 1> b;
  std::vector<double> r(n), g(n), gx(n), gy(n), wgt(n, 1.0), taper(n, 1.0);
  if (o.taper > 0)
    for (int k = 0; k < n; ++k) taper[k] = std::exp(-(du[k] * du[k] + dv[k] * dv[k]) / (2 * o.taper * o.taper));
  wgt = taper;
  bool converged = false;
  Eigen::Matrix<double, Eigen::Dynamic, 8> Jm(n, 8), WJ(n, 8);
  Eigen::VectorXd wv(n), rv(n);
  double sum_wr2 = 0;
  auto evaluate = [&](const Eigen::Matrix<double, 8, 1>& p) -> bool {
    for (int k = 0; k < n; ++k) {
      double qx = p(0) + p(2) * du[k] + p(3) * dv[k];
      double qy = p(1) + p(4) * du[k] + p(5) * dv[k];
      double v, vx, vy;
      if (!bicubic(img2, qx, qy, v, &vx, &vy)) return false;
      g[k] = (v - m2) * inv_s2;
      gx[k] = vx * inv_s2;
      gy[k] = vy * inv_s2;
      r[k] = p(6) + p(7) * g[k] - t[k];
    }
    return true;
  };
  int it = 0;
  for (; it < o.max_iterations; ++it) {
    if (!evaluate(th)) {
      res.status = LsmStatus::OutOfImage;
      return res;
    }
    // IRLS weights: plain least squares for the first two iterations, then L1
    if (o.l1 && it >= 2)
      for (int k = 0; k < n; ++k) wgt[k] = taper[k] / std::max(std::abs(r[k]), o.eps);
    const double r1 = th(7);
    for (int k = 0; k < n; ++k) {
      Jm.row(k) << r1 * gx[k], r1 * gy[k], r1 * gx[k] * du[k], r1 * gx[k] * dv[k], r1 * gy[k] * du[k], r1 * gy[k] * dv[k], 1.0, g[k];
      wv(k) = wgt[k];
      rv(k) = r[k];
    }
    WJ = Jm.array().colwise() * wv.array();
    N.noalias() = WJ.transpose() * Jm;
    b.noalias() = WJ.transpose() * rv;
    Eigen::LDLT<Eigen::Matrix<double, 8, 8>> ldlt(N);
    if (ldlt.info() != Eigen::Success) {
      res.status = LsmStatus::Diverged;
      return res;
    }
    Eigen::Matrix<double, 8, 1> delta = -ldlt.solve(b);
    if (!delta.allFinite()) {
      res.status = LsmStatus::Diverged;
      return res;
    }
    // damp wild steps of the shift
    double step = delta.head<2>().norm();
    if (step > 1.0) delta *= 1.0 / step;
    th += delta;
    if ((th.head<2>() - p2).norm() > 3 * o.max_shift + 2) {
      res.status = LsmStatus::Diverged;
      return res;
    }
    if (step < o.tolerance && (!o.l1 || it >= 3)) {
      converged = true;
      ++it;
      break;
    }
  }
  res.iterations = it;
  res.p2 = th.head<2>();
  res.A << th(2), th(3), th(4), th(5);
  res.r0 = th(6);
  res.r1 = th(7);
  if (!converged) {
    res.status = LsmStatus::NotConverged;
    return res;
  }
  // final residuals, covariance and correlation at the solution
  if (!evaluate(th)) {
    res.status = LsmStatus::OutOfImage;
    return res;
  }
  {
    sum_wr2 = 0;
    const double r1 = th(7);
    for (int k = 0; k < n; ++k) {
      Jm.row(k) << r1 * gx[k], r1 * gy[k], r1 * gx[k] * du[k], r1 * gx[k] * dv[k], r1 * gy[k] * du[k], r1 * gy[k] * dv[k], 1.0, g[k];
      wv(k) = wgt[k];
      sum_wr2 += wgt[k] * r[k] * r[k];
    }
    WJ = Jm.array().colwise() * wv.array();
    N.noalias() = WJ.transpose() * Jm;
    Eigen::Matrix<double, 8, 8> C = N.ldlt().solve(Eigen::Matrix<double, 8, 8>::Identity());
    double s0 = sum_wr2 / std::max(1, n - 8);
    double var = s0 * 0.5 * (C(0, 0) + C(1, 1));
    res.sigma = var > 0 && std::isfinite(var) ? std::sqrt(var) : 0;
  }
  {
    double mg = 0;
    for (double v : g) mg += v;
    mg /= n;
    double sgg = 0, stg = 0, stt = 0;
    for (int k = 0; k < n; ++k) {
      sgg += (g[k] - mg) * (g[k] - mg);
      stg += (g[k] - mg) * t[k];
      stt += t[k] * t[k];
    }
    res.corr = sgg > 0 ? stg / std::sqrt(sgg * stt) : 0;
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
  if (res.corr < o.min_corr) {
    res.status = LsmStatus::LowCorrelation;
    return res;
  }
  res.status = LsmStatus::Ok;
  return res;
}

}  // namespace tpkit
