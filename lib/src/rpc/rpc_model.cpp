#include "tpkit/rpc/rpc_model.hpp"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "tpkit/core/error.hpp"
#include "tpkit/core/text_table.hpp"

namespace tpkit {

Eigen::Vector2d RpcModel::project(double lon, double lat, double h) const {
  const double llh[3] = {lon, lat, h};
  double xy[2];
  project_t(llh, xy);
  return {xy[0], xy[1]};
}

Eigen::Vector2d RpcModel::project(const Eigen::Vector3d& llh, Eigen::Matrix<double, 2, 3>& J) const {
  using Jet = ceres::Jet<double, 3>;
  Jet in[3], out[2];
  for (int i = 0; i < 3; ++i) in[i] = Jet(llh[i], i);
  project_t(in, out);
  for (int r = 0; r < 2; ++r) J.row(r) = out[r].v.transpose();
  return {out[0].a, out[1].a};
}

Eigen::Vector2d RpcModel::direct(double x, double y, double h) const {
  double t[20];
  rpc_terms((x - samp_off) / samp_scale, (y - line_off) / line_scale, (h - height_off) / height_scale, t);
  return {rpc_eval(lon_num, t) / rpc_eval(lon_den, t) * lon_scale + lon_off,
          rpc_eval(lat_num, t) / rpc_eval(lat_den, t) * lat_scale + lat_off};
}

Eigen::Vector2d RpcModel::localize(double x, double y, double h) const {
  Eigen::Vector2d ll(lon_off, lat_off);
  if (has_direct) {
    Eigen::Vector2d d = direct(x, y, h);
    if (d.allFinite()) ll = d;
  }
  const Eigen::Vector2d target(x, y);
  Eigen::Matrix<double, 2, 3> J;
  for (int it = 0; it < 60; ++it) {
    Eigen::Vector2d r = target - project(Eigen::Vector3d(ll[0], ll[1], h), J);
    if (!r.allFinite()) break;
    if (r.norm() < 1e-9) return ll;
    Eigen::Matrix2d A = J.leftCols<2>();
    Eigen::Vector2d step = A.fullPivLu().solve(r);
    if (!step.allFinite()) break;
    // keep a step within the model's normalization box (a poor start must not leave the model's domain)
    double limit = 0.5 * std::max(lon_scale, lat_scale);
    if (step.norm() > limit) step *= limit / step.norm();
    ll += step;
  }
  if ((project(ll[0], ll[1], h) - target).norm() < 1e-6) return ll;
  throw NumericalError("RPC localization of pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") at height " +
                       std::to_string(h) + " m did not converge");
}

bool RpcModel::outside_validity_box(const Eigen::Vector3d& llh, double margin) const {
  const double L = (llh[0] - lon_off) / lon_scale, P = (llh[1] - lat_off) / lat_scale, H = (llh[2] - height_off) / height_scale;
  return !(std::fabs(L) <= margin && std::fabs(P) <= margin && std::fabs(H) <= margin);
}

std::string RpcModel::outside_domain(const Eigen::Vector3d& llh) const {
  if (!(llh[1] >= -90 && llh[1] <= 90)) return "latitude " + format_number(llh[1]) + " is outside [-90, 90]";
  if (!(llh[0] >= -180 && llh[0] < 360)) return "longitude " + format_number(llh[0]) + " is outside [-180, 360)";
  if (outside_validity_box(llh, kFarOutsideScales))
    return "(" + format_number(llh[0]) + ", " + format_number(llh[1]) + ", " + format_number(llh[2]) + ") is more than " +
           format_number(kFarOutsideScales) + " scales from the model's offsets (lon " + format_number(lon_off) + " +- " +
           format_number(lon_scale) + ", lat " + format_number(lat_off) + " +- " + format_number(lat_scale) + ", h " +
           format_number(height_off) + " +- " + format_number(height_scale) + "): the model says nothing there";
  return "";
}

bool RpcModel::operator==(const RpcModel& o) const {
  auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  const double a[] = {err_bias, err_rand, line_off, samp_off, lat_off, lon_off, height_off,
                      line_scale, samp_scale, lat_scale, lon_scale, height_scale};
  const double b[] = {o.err_bias, o.err_rand, o.line_off, o.samp_off, o.lat_off, o.lon_off, o.height_off,
                      o.line_scale, o.samp_scale, o.lat_scale, o.lon_scale, o.height_scale};
  for (int i = 0; i < 12; ++i)
    if (!same(a[i], b[i])) return false;
  if (line_num != o.line_num || line_den != o.line_den || samp_num != o.samp_num || samp_den != o.samp_den)
    return false;
  if (has_direct != o.has_direct) return false;
  return !has_direct ||
         (lon_num == o.lon_num && lon_den == o.lon_den && lat_num == o.lat_num && lat_den == o.lat_den);
}

std::optional<Eigen::Vector2d> epipolar_point(const RpcModel& a, const RpcModel& b, double x, double y, double h) {
  try {
    const Eigen::Vector2d ll = a.localize(x, y, h);
    return b.project(ll[0], ll[1], h);
  } catch (const NumericalError&) {
    return std::nullopt;
  }
}

std::vector<Eigen::Vector3d> epipolar_curve(const RpcModel& a, const RpcModel& b, double x, double y, double h_lo,
                                            double h_hi, int samples) {
  samples = std::max(samples, 2);
  std::vector<Eigen::Vector3d> out;
  out.reserve(samples);
  for (int k = 0; k < samples; ++k) {
    const double h = h_lo + (h_hi - h_lo) * k / (samples - 1);
    if (const auto q = epipolar_point(a, b, x, y, h)) out.emplace_back(q->x(), q->y(), h);
  }
  return out;
}

double epipolar_distance(const RpcModel& a, const RpcModel& b, const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                         double h_lo, double h_hi, int samples) {
  auto curve = epipolar_curve(a, b, p[0], p[1], h_lo, h_hi, samples);
  if (curve.empty()) return std::numeric_limits<double>::infinity();
  if (curve.size() == 1) return (curve[0].head<2>() - q).norm();
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < curve.size(); ++i) {
    Eigen::Vector2d s = curve[i].head<2>(), e = curve[i + 1].head<2>(), d = e - s;
    double t = d.squaredNorm() > 0 ? std::clamp((q - s).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (s + t * d - q).norm());
  }
  return best;
}

namespace {

struct FitSample {
  Eigen::Vector3d norm_ground;  // (L, P, H)
  Eigen::Vector2d pixel;
};

// One rational function num / den (den[0] = 1) fitted to normalized values r of the samples, by
// iteratively reweighted linear least squares (weights 1 / den of the previous round, Tao & Hu 2001).
void fit_rational(const std::vector<FitSample>& s, const std::vector<double>& r, RpcPoly& num, RpcPoly& den) {
  const int n = static_cast<int>(s.size());
  std::vector<std::array<double, 20>> terms(n);
  for (int i = 0; i < n; ++i) rpc_terms(s[i].norm_ground[0], s[i].norm_ground[1], s[i].norm_ground[2], terms[i].data());
  std::vector<double> w(n, 1.0);
  const double ridge = 1e-10;
  for (int round = 0; round < 4; ++round) {
    Eigen::MatrixXd A(n + 39, 39);
    Eigen::VectorXd b(n + 39);
    A.setZero();
    b.setZero();
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < 20; ++j) A(i, j) = w[i] * terms[i][j];
      for (int j = 1; j < 20; ++j) A(i, 19 + j) = -w[i] * r[i] * terms[i][j];
      b[i] = w[i] * r[i];
    }
    for (int j = 0; j < 39; ++j) A(n + j, j) = std::sqrt(ridge);
    Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
    for (int j = 0; j < 20; ++j) num[j] = c[j];
    den[0] = 1;
    for (int j = 1; j < 20; ++j) den[j] = c[19 + j];
    for (int i = 0; i < n; ++i) {
      double d = rpc_eval(den, terms[i].data());
      w[i] = std::fabs(d) > 1e-12 ? 1.0 / d : 1.0;
    }
  }
}

std::vector<Eigen::Vector3d> grid(const RpcFitVolume& v, bool check) {
  std::vector<Eigen::Vector3d> g;
  const int n = check ? v.n - 1 : v.n, nh = check ? v.nh - 1 : v.nh;
  const double o = check ? 0.5 : 0.0;
  for (int k = 0; k < nh; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        double fi = (i + o) / (v.n - 1), fj = (j + o) / (v.n - 1), fk = (k + o) / std::max(v.nh - 1, 1);
        g.emplace_back(v.lon0 + fi * (v.lon1 - v.lon0), v.lat0 + fj * (v.lat1 - v.lat0), v.h0 + fk * (v.h1 - v.h0));
      }
  return g;
}

}  // namespace

RpcFit fit_rpc(const std::function<Eigen::Vector2d(const Eigen::Vector3d& llh)>& ground_to_image,
               const RpcFitVolume& v) {
  if (!(v.lon1 > v.lon0) || !(v.lat1 > v.lat0) || !(v.h1 >= v.h0) || v.n < 5 || v.nh < 2)
    throw NumericalError("RPC fit: empty or degenerate ground volume");
  RpcFit fit;
  RpcModel& m = fit.model;
  m.lon_off = 0.5 * (v.lon0 + v.lon1);
  m.lat_off = 0.5 * (v.lat0 + v.lat1);
  m.height_off = 0.5 * (v.h0 + v.h1);
  m.lon_scale = 0.5 * (v.lon1 - v.lon0);
  m.lat_scale = 0.5 * (v.lat1 - v.lat0);
  m.height_scale = std::max(0.5 * (v.h1 - v.h0), 1.0);
  auto pts = grid(v, false);
  std::vector<FitSample> s;
  s.reserve(pts.size());
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& g : pts) {
    Eigen::Vector2d p = ground_to_image(g);
    if (!p.allFinite()) throw NumericalError("RPC fit: the camera does not see the whole volume");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    s.push_back({Eigen::Vector3d((g[0] - m.lon_off) / m.lon_scale, (g[1] - m.lat_off) / m.lat_scale,
                                 (g[2] - m.height_off) / m.height_scale),
                 p});
  }
  m.samp_off = std::round(0.5 * (lo[0] + hi[0]));
  m.line_off = std::round(0.5 * (lo[1] + hi[1]));
  m.samp_scale = std::max(std::ceil(0.5 * (hi[0] - lo[0])), 1.0);
  m.line_scale = std::max(std::ceil(0.5 * (hi[1] - lo[1])), 1.0);
  std::vector<double> rs(s.size()), rl(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    rs[i] = (s[i].pixel[0] - m.samp_off) / m.samp_scale;
    rl[i] = (s[i].pixel[1] - m.line_off) / m.line_scale;
  }
  fit_rational(s, rs, m.samp_num, m.samp_den);
  fit_rational(s, rl, m.line_num, m.line_den);
  double sum = 0;
  auto check = grid(v, true);
  for (const auto& g : check) {
    double e = (m.project(g) - ground_to_image(g)).norm();
    sum += e * e;
    fit.max_px = std::max(fit.max_px, e);
  }
  fit.rms_px = std::sqrt(sum / std::max<size_t>(check.size(), 1));
  return fit;
}

RpcFitVolume rpc_volume(const RpcModel& m) {
  RpcFitVolume v;
  v.lon0 = m.lon_off - m.lon_scale;
  v.lon1 = m.lon_off + m.lon_scale;
  v.lat0 = m.lat_off - m.lat_scale;
  v.lat1 = m.lat_off + m.lat_scale;
  v.h0 = m.height_off - m.height_scale;
  v.h1 = m.height_off + m.height_scale;
  return v;
}

namespace {
// Exponents of (L, P, H) of each RPC00B term, in rpc_terms() order.
constexpr int kTermPowers[20][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1},
                                    {2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {1, 1, 1}, {3, 0, 0}, {1, 2, 0}, {1, 0, 2},
                                    {2, 1, 0}, {0, 3, 0}, {0, 1, 2}, {2, 0, 1}, {0, 2, 1}, {0, 0, 3}};
int term_index(int i, int j, int k) {
  for (int t = 0; t < 20; ++t)
    if (kTermPowers[t][0] == i && kTermPowers[t][1] == j && kTermPowers[t][2] == k) return t;
  return -1;
}
double binomial(int n, int k) { return n == 3 && (k == 1 || k == 2) ? 3.0 : n == 2 && k == 1 ? 2.0 : 1.0; }

// c(u) with u = b + a * u' for each variable, as a polynomial in u'.
RpcPoly substitute(const RpcPoly& c, const double a[3], const double b[3]) {
  RpcPoly out{};
  for (int t = 0; t < 20; ++t) {
    if (c[t] == 0.0) continue;
    const int* e = kTermPowers[t];
    for (int i = 0; i <= e[0]; ++i)
      for (int j = 0; j <= e[1]; ++j)
        for (int k = 0; k <= e[2]; ++k) {
          const double w = binomial(e[0], i) * std::pow(a[0], i) * std::pow(b[0], e[0] - i) * binomial(e[1], j) *
                           std::pow(a[1], j) * std::pow(b[1], e[1] - j) * binomial(e[2], k) * std::pow(a[2], k) *
                           std::pow(b[2], e[2] - k);
          out[term_index(i, j, k)] += c[t] * w;
        }
  }
  return out;
}
}  // namespace

RpcModel renormalized_rpc(const RpcModel& m, const RpcModel& to) {
  RpcModel r = m;
  r.line_off = to.line_off;
  r.samp_off = to.samp_off;
  r.lat_off = to.lat_off;
  r.lon_off = to.lon_off;
  r.height_off = to.height_off;
  r.line_scale = to.line_scale;
  r.samp_scale = to.samp_scale;
  r.lat_scale = to.lat_scale;
  r.lon_scale = to.lon_scale;
  r.height_scale = to.height_scale;
  r.has_direct = false;
  // old normalized = b + a * new normalized, for (L, P, H) = (lon, lat, h)
  const double a[3] = {to.lon_scale / m.lon_scale, to.lat_scale / m.lat_scale, to.height_scale / m.height_scale};
  const double b[3] = {(to.lon_off - m.lon_off) / m.lon_scale, (to.lat_off - m.lat_off) / m.lat_scale,
                       (to.height_off - m.height_off) / m.height_scale};
  // x = off + scale * N / D = off' + scale' * (scale * N + (off - off') * D) / (scale' * D)
  auto image_side = [&](const RpcPoly& num, const RpcPoly& den, double off, double scale, double off2, double scale2,
                        RpcPoly& num_out, RpcPoly& den_out) {
    const RpcPoly n = substitute(num, a, b), d = substitute(den, a, b);
    if (d[0] == 0.0) throw NumericalError("renormalized RPC: the denominator is 0 at the new centre");
    for (int t = 0; t < 20; ++t) {
      num_out[t] = (scale * n[t] + (off - off2) * d[t]) / (scale2 * d[0]);
      den_out[t] = d[t] / d[0];
    }
  };
  image_side(m.samp_num, m.samp_den, m.samp_off, m.samp_scale, to.samp_off, to.samp_scale, r.samp_num, r.samp_den);
  image_side(m.line_num, m.line_den, m.line_off, m.line_scale, to.line_off, to.line_scale, r.line_num, r.line_den);
  return r;
}

}  // namespace tpkit
