// See cluster_exhaustive.hpp.
#include "tpkit/cluster/cluster_exhaustive.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "tpkit/cluster/cluster_verdict.hpp"

namespace tpkit {

long exhaustive_hypothesis_count(long na, long nb) {
  if (na < 4 || nb < 4) return 0;
  const long double c = static_cast<long double>(na) * (na - 1) * (na - 2) * (na - 3) / 24.0L;
  const long double p = static_cast<long double>(nb) * (nb - 1) * (nb - 2) * (nb - 3);
  const long double n = c * p;
  return n >= static_cast<long double>(std::numeric_limits<long>::max()) ? std::numeric_limits<long>::max()
                                                                         : static_cast<long>(n);
}

namespace {

// The matrix taking e1, e2, e3 and (1, 1, 1) to the four points; false when three of them are collinear.
bool basis(const Eigen::MatrixX2d& P, const std::array<int, 4>& q, Eigen::Matrix3d& M) {
  Eigen::Matrix3d C;
  for (int k = 0; k < 3; ++k) C.col(k) << P(q[k], 0), P(q[k], 1), 1.0;
  const Eigen::Vector3d p4(P(q[3], 0), P(q[3], 1), 1.0);
  // collinear triples, relative to the points' spread
  double span2 = 0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) span2 = std::max(span2, (P.row(q[a]) - P.row(q[b])).squaredNorm());
  const Eigen::Vector3d P4[4] = {C.col(0), C.col(1), C.col(2), p4};
  for (int m = 0; m < 4; ++m) {
    int o[3], n = 0;
    for (int k = 0; k < 4; ++k)
      if (k != m) o[n++] = k;
    const double area2 = std::fabs((P4[o[1]] - P4[o[0]]).head<2>().x() * (P4[o[2]] - P4[o[0]]).head<2>().y() -
                                   (P4[o[1]] - P4[o[0]]).head<2>().y() * (P4[o[2]] - P4[o[0]]).head<2>().x());
    if (!(area2 > 1e-9 * span2)) return false;
  }
  const Eigen::Vector3d lambda = C.partialPivLu().solve(p4);
  M = C * lambda.asDiagonal();
  return M.allFinite();
}

}  // namespace

std::vector<ExhaustiveHypothesis> exhaustive_hypotheses(const ClusterCost& cost, bool allow_reflection, int keep,
                                                        long* tried) {
  const Eigen::MatrixX2d &A = cost.a(), &B = cost.b();
  const int na = static_cast<int>(A.rows()), nb = static_cast<int>(B.rows());
  std::vector<ExhaustiveHypothesis> best;
  long n_tried = 0;
  if (tried) *tried = 0;
  if (na < 4 || nb < 4) return best;
  const MapCheck check(A, B);
  const double density = nb / check.area_b(), spacing = std::sqrt(check.area_b() / nb);
  // every 4 points of A with the inverse of its basis (C(|A|, 4) of them: at most a few MB within the
  // budget), then every ordered 4 points of B against them
  std::vector<std::array<int, 4>> qas;
  std::vector<Eigen::Matrix3d> mais;
  for (int i0 = 0; i0 < na; ++i0)
    for (int i1 = i0 + 1; i1 < na; ++i1)
      for (int i2 = i1 + 1; i2 < na; ++i2)
        for (int i3 = i2 + 1; i3 < na; ++i3) {
          Eigen::Matrix3d Ma;
          if (basis(A, {i0, i1, i2, i3}, Ma)) qas.push_back({i0, i1, i2, i3}), mais.push_back(Ma.inverse());
        }
  std::vector<Eigen::Vector3d> ha(static_cast<size_t>(na));
  for (int i = 0; i < na; ++i) ha[static_cast<size_t>(i)] << A(i, 0), A(i, 1), 1.0;
  std::vector<double> d;
  std::vector<std::pair<int, int>> extra;
  std::vector<int> claim(static_cast<size_t>(nb));  // -2: one of the four; else the index into extra
  std::vector<double> dist_of;                        // squared distance of each claim
  for (int b0 = 0; b0 < nb; ++b0)
    for (int b1 = 0; b1 < nb; ++b1)
      for (int b2 = 0; b2 < nb; ++b2)
        for (int b3 = 0; b3 < nb; ++b3) {
          if (b0 == b1 || b0 == b2 || b0 == b3 || b1 == b2 || b1 == b3 || b2 == b3) continue;
          const std::array<int, 4> qb = {b0, b1, b2, b3};
          Eigen::Matrix3d Mb;
          if (!basis(B, qb, Mb)) continue;
          for (size_t u = 0; u < qas.size(); ++u) {
            const std::array<int, 4>& qa = qas[u];
            const int i0 = qa[0], i1 = qa[1], i2 = qa[2], i3 = qa[3];
            const Eigen::Matrix3d H = Mb * mais[u];
            ++n_tried;
            // all of A on one side of the line at infinity; orientation kept unless mirrors are allowed
            const double w0 = H.row(2).dot(ha[static_cast<size_t>(i0)]);
            bool torn = !(w0 != 0);
            for (int i = 0; i < na && !torn; ++i) torn = !(H.row(2).dot(ha[static_cast<size_t>(i)]) * w0 > 0);
            if (torn) continue;
            if (!allow_reflection && !(H.determinant() * w0 > 0)) continue;
            // the other points of A: nearest free point of B, each point of B given to the nearest claim
            // only (a map that squeezes A onto one point of B matches one point, not all)
            std::fill(claim.begin(), claim.end(), -1);
            for (int k = 0; k < 4; ++k) claim[static_cast<size_t>(qb[k])] = -2;
            d.assign(4, 0.0);
            extra.clear();
            for (int i = 0; i < na; ++i) {
              if (i == i0 || i == i1 || i == i2 || i == i3) continue;
              const Eigen::Vector3d q = H * ha[static_cast<size_t>(i)];
              const Eigen::Vector2d x(q.x() / q.z(), q.y() / q.z());
              double bd = std::numeric_limits<double>::infinity();
              int bj = -1;
              for (int j = 0; j < nb; ++j)
                if (claim[static_cast<size_t>(j)] != -2) {
                  const double e = (B.row(j).transpose() - x).squaredNorm();
                  if (e < bd) bd = e, bj = j;
                }
              if (bj < 0) continue;
              int& c = claim[static_cast<size_t>(bj)];
              if (c >= 0 && dist_of[static_cast<size_t>(c)] <= bd) continue;  // a nearer claim holds it
              c = static_cast<int>(extra.size());
              dist_of.resize(extra.size() + 1);
              dist_of[extra.size()] = bd;
              extra.emplace_back(i, bj);
            }
            // drop the claims that lost their point of B
            for (size_t k = 0; k < extra.size(); ++k)
              if (claim[static_cast<size_t>(extra[k].second)] == static_cast<int>(k)) d.push_back(std::sqrt(dist_of[k]));
              else extra[k].second = -1;
            extra.erase(std::remove_if(extra.begin(), extra.end(), [](const std::pair<int, int>& e) { return e.second < 0; }),
                        extra.end());
            // nothing beyond the four near enough to matter: not worth the statistic
            double nearest = std::numeric_limits<double>::infinity();
            for (size_t k = 4; k < d.size(); ++k) nearest = std::min(nearest, d[k]);
            if (!(nearest < 0.5 * spacing) && d.size() > 4) continue;
            const Significance s = match_significance(na, d, density, spacing);
            if (static_cast<int>(best.size()) == keep && !(s.log10_tail < best.back().log10_tail)) continue;
            if (!check(H).empty()) continue;  // torn or collapsed (cluster_verdict.hpp)
            ExhaustiveHypothesis h;
            h.H = H;
            for (int k = 0; k < 4; ++k) h.pairs.emplace_back(qa[k], qb[k]);
            for (size_t k = 0; k < extra.size(); ++k)
              if (d[k + 4] <= s.radius) h.pairs.push_back(extra[k]);
            std::sort(h.pairs.begin(), h.pairs.end());
            h.log10_tail = s.log10_tail;
            // one map comes from every four of its matches: keep it once, from its best four
            auto same = std::find_if(best.begin(), best.end(), [&](const ExhaustiveHypothesis& e) { return e.pairs == h.pairs; });
            if (same != best.end()) {
              if (!(h.log10_tail < same->log10_tail)) continue;
              best.erase(same);
            }
            auto at = std::upper_bound(best.begin(), best.end(), h.log10_tail,
                                       [](double v, const ExhaustiveHypothesis& e) { return v < e.log10_tail; });
            best.insert(at, std::move(h));
            if (static_cast<int>(best.size()) > keep) best.pop_back();
          }
        }
  if (tried) *tried = n_tried;
  return best;
}

}  // namespace tpkit
