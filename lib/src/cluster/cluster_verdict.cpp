#include "tpkit/cluster/cluster_verdict.hpp"

#include <Eigen/Dense>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace tpkit {

namespace {
using Pt = Eigen::Vector2d;

// Convex hull (Andrew's monotone chain), counter-clockwise, no repeated end point.
std::vector<Pt> hull(std::vector<Pt> p) {
  std::sort(p.begin(), p.end(), [](const Pt& a, const Pt& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  if (p.size() < 3) return p;
  auto cross = [](const Pt& o, const Pt& a, const Pt& b) { return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x(); };
  std::vector<Pt> h(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

std::vector<Pt> hull(const Eigen::MatrixX2d& P) {
  std::vector<Pt> p(static_cast<size_t>(P.rows()));
  for (Eigen::Index i = 0; i < P.rows(); ++i) p[static_cast<size_t>(i)] = P.row(i).transpose();
  return hull(std::move(p));
}

double area(const std::vector<Pt>& poly) {
  double s = 0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const Pt &a = poly[i], &b = poly[(i + 1) % poly.size()];
    s += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::fabs(s);
}

constexpr double kPi = 3.14159265358979323846;

bool inside(const std::vector<Pt>& poly, const Pt& q) {  // convex, counter-clockwise
  for (size_t i = 0; i < poly.size(); ++i) {
    const Pt &a = poly[i], &b = poly[(i + 1) % poly.size()];
    if ((b - a).x() * (q - a).y() - (b - a).y() * (q - a).x() < 0) return false;
  }
  return true;
}

// The points' images under H; false when the line at infinity of H separates any two of them (or
// passes through one): then H tears the cluster apart.
bool carry(const Eigen::Matrix3d& H, const std::vector<Pt>& in, std::vector<Pt>& out) {
  out.clear();
  int sign = 0;
  for (const Pt& p : in) {
    const Eigen::Vector3d q = H * Eigen::Vector3d(p.x(), p.y(), 1);
    const int s = q.z() > 0 ? 1 : q.z() < 0 ? -1 : 0;
    if (s == 0 || (sign != 0 && s != sign)) return false;
    sign = s;
    out.emplace_back(q.x() / q.z(), q.y() / q.z());
  }
  return true;
}

}  // namespace

MapCheck::MapCheck(const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B)
    : hull_a_(hull(A)), hull_b_(hull(B)), area_a_(area(hull_a_)), area_b_(area(hull_b_)) {}

std::string MapCheck::operator()(const Eigen::Matrix3d& H) const {
  if (!H.allFinite() || std::fabs(H.determinant()) < 1e-300) return "singular homography";
  std::vector<Pt> ha_mapped, hb_mapped;
  // the line at infinity crosses a hull iff it separates two of its vertices
  if (!carry(H, hull_a_, ha_mapped)) return "its line at infinity crosses cluster A";
  if (!carry(H.inverse(), hull_b_, hb_mapped)) return "the line at infinity of its inverse crosses cluster B";
  if (!(area_a_ > 0) || !(area_b_ > 0)) return "a cluster has no area";
  // h(hull A) is the hull of the mapped vertices (on one side of its line at infinity a homography keeps
  // convexity); a mapped area far below both clusters' shows a cluster collapsed onto a few points
  const double fa = area(hull(ha_mapped)), fb = area(hull(hb_mapped));
  const double floor = kMinAreaRatio * std::min(area_a_, area_b_);
  if (!(fa >= floor)) return "it collapses cluster A (mapped area " + std::to_string(fa) + " px^2)";
  if (!(fb >= floor)) return "its inverse collapses cluster B (mapped area " + std::to_string(fb) + " px^2)";
  return "";
}

double MapCheck::outside_b(const Eigen::Vector2d& q) const {
  if (inside(hull_b_, q)) return 0;
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < hull_b_.size(); ++i) {
    const Pt &a = hull_b_[i], &b = hull_b_[(i + 1) % hull_b_.size()];
    const Pt ab = b - a;
    const double t = ab.squaredNorm() > 0 ? std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * ab - q).norm());
  }
  return best;
}

std::string degeneracy(const Eigen::Matrix3d& H, const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B) {
  return MapCheck(A, B)(H);
}

double log10_binomial_tail(int n, int k, double p) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (k <= 0) return 0;
  if (k > n) return -kInf;
  if (!(p > 0)) return -kInf;
  if (p >= 1) return 0;
  // terms t_j = C(n, j) p^j q^(n-j) summed from the largest outwards, in units of the first term, until
  // they stop counting (they fall geometrically away from the mode): O(n p q)^(1/2) terms at worst
  const double lp = std::log(p), lq = std::log1p(-p), lr = lp - lq;
  auto log_term = [&](int j) { return std::lgamma(n + 1.0) - std::lgamma(j + 1.0) - std::lgamma(n - j + 1.0) + j * lp + (n - j) * lq; };
  const int mode = static_cast<int>(std::floor((n + 1) * p));
  if (k > mode) {  // the upper tail itself: decreasing terms from j = k up
    double sum = 1, t = 1;
    for (int j = k; j < n; ++j) {
      t *= std::exp(std::log(static_cast<double>(n - j) / (j + 1)) + lr);
      sum += t;
      if (t < 1e-17 * sum) break;
    }
    return std::min(0.0, (log_term(k) + std::log(sum)) / std::log(10.0));
  }
  // k <= mode: 1 - P(K <= k - 1), decreasing terms from j = k - 1 down
  const double l0 = log_term(k - 1);
  double sum = 1, t = 1;
  for (int j = k - 1; j > 0; --j) {
    t *= std::exp(std::log(static_cast<double>(j) / (n - j + 1)) - lr);
    sum += t;
    if (t < 1e-17 * sum) break;
  }
  const double lower = std::exp(l0 + std::log(sum));
  return lower >= 1 ? 0 : std::log1p(-lower) / std::log(10.0);
}

Significance match_significance(int n, std::vector<double> d, double density, double spacing, int fitted) {
  Significance s;
  s.radii = std::max(1, n - fitted);
  std::sort(d.begin(), d.end());
  const double floor = 1e-6 * spacing;
  s.log10_tail = 0;
  bool any = false;
  for (size_t i = static_cast<size_t>(fitted); i < d.size() && static_cast<int>(i) < n; ++i) {  // k = i + 1 matches within d_k
    const int k = static_cast<int>(i) + 1;
    if (i + 1 < d.size() && d[i + 1] == d[i]) continue;  // ties: the largest k at that radius
    const double r = std::max(d[i], floor);
    // h is fitted to its matches (least squares, 2 s parameters): k matches' 2k residuals keep only
    // (2k - 2s) / 2k of their squared size, so k matches within r are as likely by chance as k independent
    // points within r / sqrt(1 - s / k) (homography, s = 4: for k = 5, 2.2 r; for k = 100, 1.02 r)
    const double r_chance = r / std::sqrt(1.0 - static_cast<double>(fitted) / k);
    const double p = -std::expm1(-kPi * r_chance * r_chance * density);
    const double lt = log10_binomial_tail(n - fitted, k - fitted, p);
    if (!any || lt < s.log10_tail) s = {lt, k, r, p, s.radii}, any = true;
  }
  if (!any) {  // nothing beyond the s matches any h fits: no evidence (the smallest radius, for the report)
    s.inliers = static_cast<int>(std::min<size_t>(d.size(), static_cast<size_t>(std::max(n, 0))));
    s.radius = d.empty() ? 0 : std::max(d.back(), floor);
    s.p = -std::expm1(-kPi * s.radius * s.radius * density);
  }
  return s;
}

Verdict judge_homography(const ClusterCost& cost, const Eigen::Matrix3d& H, const VerdictOptions& opt) {
  Verdict v;
  const Eigen::MatrixX2d &A = cost.a(), &B = cost.b();
  const MapCheck check(A, B);
  v.degenerate = check(H);
  if (!v.degenerate.empty()) {
    v.log10_odds = -std::numeric_limits<double>::infinity();
    return v;
  }
  // chance matches are spread over the region where B's points could have been: B's image when it is
  // known (AC-RANSAC's and astrometry.net's field), else B's convex hull
  const double domain = std::max(check.area_b(), opt.domain_area_b);
  const double m = static_cast<double>(B.rows()), density = m / domain, spacing = std::sqrt(check.area_b() / m);
  // every point of A is a trial: a map chosen to fit a few points must not be judged only on the points
  // it keeps inside B (an unrelated 100-point pair stretched 6 times across B kept 19 points of A there,
  // 11 of them matched within 2.8 px: log10 odds 4.0 on those 19, -2 on all 100). The points that land
  // in hull B (or within a quarter spacing of it: hull corners, which noise puts just outside) are
  // counted for the report and for "undetermined".
  const int n = static_cast<int>(A.rows());
  for (Eigen::Index i = 0; i < A.rows(); ++i) {
    const Eigen::Vector3d q = H * Eigen::Vector3d(A(i, 0), A(i, 1), 1);
    v.mapped_into_b += check.outside_b(Pt(q.x() / q.z(), q.y() / q.z())) <= kCandidateMargin * spacing;
  }
  std::vector<double> d;
  for (const MutualPair& mp : mutual_pairs(cost, H)) d.push_back(mp.d);
  const int fitted = cluster_model_points(opt.model);
  const Significance s = match_significance(n, std::move(d), density, spacing, fitted);
  v.candidates = n;
  v.inliers = s.inliers;
  v.radius_px = s.radius;
  v.expected = std::min(n, fitted) + std::max(0, n - fitted) * s.p;
  const double tests = static_cast<double>(s.radii) * static_cast<double>(std::max(1L, opt.hypotheses));
  v.log10_odds = -(std::log10(tests) + s.log10_tail);
  if (v.mapped_into_b <= fitted)
    v.undetermined = "only " + std::to_string(v.mapped_into_b) + " points of cluster A map into cluster B, and any " +
                     std::to_string(fitted) + " correspondences fit " + (opt.model == ClusterModel::Affine ? "an " : "a ") +
                     cluster_model_name(opt.model) + " exactly";
  v.accepted = v.undetermined.empty() && v.log10_odds >= opt.min_log10_odds;
  return v;
}

RegionSupport::RegionSupport(const ClusterCost& cost)
    : cost_(cost), check_(cost.a(), cost.b()), density_(static_cast<double>(cost.b().rows()) / check_.area_b()),
      spacing_(std::sqrt(check_.area_b() / static_cast<double>(cost.b().rows()))) {}

double RegionSupport::log10_odds(const Eigen::Matrix3d& H, const Eigen::Vector2d& center, double radius) const {
  const Eigen::MatrixX2d &A = cost_.a(), &B = cost_.b();
  Eigen::FullPivLU<Eigen::Matrix3d> lu(H);
  if (!H.allFinite() || !lu.isInvertible()) return -std::numeric_limits<double>::infinity();
  const Eigen::Matrix3d Hi = lu.inverse();
  const double r2 = radius * radius;
  int n = 0;
  std::vector<double> d;
  for (Eigen::Index i = 0; i < A.rows(); ++i) {
    if ((A.row(i).transpose() - center).squaredNorm() > r2) continue;
    const Eigen::Vector3d q = H * Eigen::Vector3d(A(i, 0), A(i, 1), 1);
    const Pt qa(q.x() / q.z(), q.y() / q.z());
    if (!qa.allFinite() || !(check_.outside_b(qa) <= kCandidateMargin * spacing_)) continue;
    ++n;
    double d2 = 0, e2 = 0;
    const int j = cost_.nearest_b(qa.data(), &d2);
    const Eigen::Vector3d w = Hi * Eigen::Vector3d(B(j, 0), B(j, 1), 1);
    const double back[2] = {w.x() / w.z(), w.y() / w.z()};
    if (std::isfinite(back[0]) && std::isfinite(back[1]) && cost_.nearest_a(back, &e2) == static_cast<int>(i))
      d.push_back(std::sqrt(d2));
  }
  const Significance s = match_significance(n, std::move(d), density_, spacing_);
  return -(std::log10(static_cast<double>(s.radii)) + s.log10_tail);
}

}  // namespace tpkit
