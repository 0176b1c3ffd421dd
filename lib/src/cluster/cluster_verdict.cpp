#include "tpkit/cluster_verdict.hpp"

#include <Eigen/Dense>
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

// log of the binomial upper tail P(K >= k), K ~ Bin(n, p), summed in log space.
double log_binomial_tail(int n, int k, double p) {
  if (k <= 0) return 0;
  if (k > n) return -std::numeric_limits<double>::infinity();
  if (p <= 0) return -std::numeric_limits<double>::infinity();
  if (p >= 1) return 0;
  const double lp = std::log(p), lq = std::log1p(-p);
  double m = -std::numeric_limits<double>::infinity();
  std::vector<double> terms;
  for (int j = k; j <= n; ++j) {
    const double t = std::lgamma(n + 1.0) - std::lgamma(j + 1.0) - std::lgamma(n - j + 1.0) + j * lp + (n - j) * lq;
    terms.push_back(t);
    m = std::max(m, t);
  }
  double s = 0;
  for (double t : terms) s += std::exp(t - m);
  return std::min(0.0, m + std::log(s));
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

std::string degeneracy(const Eigen::Matrix3d& H, const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B) {
  return MapCheck(A, B)(H);
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
  const std::vector<Pt>& hb = check.hull_b();
  const double b_area = check.area_b(), m = static_cast<double>(B.rows());
  const double spacing = std::sqrt(b_area / m);
  // candidates: points of A that land inside hull B
  std::vector<char> cand(static_cast<size_t>(A.rows()), 0);
  for (Eigen::Index i = 0; i < A.rows(); ++i) {
    const Eigen::Vector3d q = H * Eigen::Vector3d(A(i, 0), A(i, 1), 1);
    cand[static_cast<size_t>(i)] = inside(hb, Pt(q.x() / q.z(), q.y() / q.z()));
  }
  const int n = static_cast<int>(std::count(cand.begin(), cand.end(), 1));
  const std::vector<MutualPair> mutual = mutual_pairs(cost, H);
  const double radii[4] = {spacing / 32, spacing / 16, spacing / 8, spacing / 4};
  const double tests = 4.0 * static_cast<double>(std::max(1L, opt.hypotheses));
  v.log10_odds = -std::numeric_limits<double>::infinity();
  for (double r : radii) {
    int k = 0;
    for (const MutualPair& mp : mutual) k += cand[static_cast<size_t>(mp.ia)] && mp.d <= r;
    const double p = -std::expm1(-3.14159265358979323846 * r * r * m / b_area);
    const double log10_tail = log_binomial_tail(n - 4, k - 4, p) / std::log(10.0);
    const double odds = -(std::log10(tests) + log10_tail);
    if (odds > v.log10_odds || v.radius_px == 0) {
      v.log10_odds = odds;
      v.inliers = k;
      v.radius_px = r;
      v.expected = 4 + std::max(0, n - 4) * p;
    }
  }
  v.candidates = n;
  v.accepted = v.log10_odds >= opt.min_log10_odds;
  return v;
}

}  // namespace tpkit
