// See cluster_exhaustive.hpp.
#include "tpkit/cluster/cluster_exhaustive.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "tpkit/cluster/cluster_verdict.hpp"

namespace tpkit {

long exhaustive_hypothesis_count(long na, long nb, ClusterModel model) {
  const int s = cluster_model_points(model);
  if (na < s || nb < s) return 0;
  long double c = 1, p = 1;
  for (int k = 0; k < s; ++k) c *= static_cast<long double>(na - k) / (k + 1), p *= static_cast<long double>(nb - k);
  const long double n = c * p;
  return n >= static_cast<long double>(std::numeric_limits<long>::max()) ? std::numeric_limits<long>::max()
                                                                         : static_cast<long>(n);
}

std::vector<ExhaustiveHypothesis> exhaustive_hypotheses(const ClusterCost& cost, bool allow_reflection, int keep,
                                                        long* tried, ClusterModel model) {
  const Eigen::MatrixX2d &A = cost.a(), &B = cost.b();
  const int na = static_cast<int>(A.rows()), nb = static_cast<int>(B.rows());
  const int s = cluster_model_points(model);
  std::vector<ExhaustiveHypothesis> best;
  long n_tried = 0;
  if (tried) *tried = 0;
  if (na < s || nb < s) return best;
  const MapCheck check(A, B);
  const double density = nb / check.area_b(), spacing = std::sqrt(check.area_b() / nb);
  // every s points of A with the inverse of its frame (C(|A|, s) of them: at most a few MB within the
  // budget), then every ordered s points of B against them
  std::vector<std::array<int, 4>> qas;
  std::vector<Eigen::Matrix3d> mais;
  std::array<int, 4> qa{0, 1, 2, 3};
  for (int k = 0; k < s; ++k) qa[k] = k;
  for (;;) {  // combinations in lexicographic order
    Eigen::Matrix3d Ma;
    if (cluster_model_frame(model, A, qa.data(), Ma)) qas.push_back(qa), mais.push_back(Ma.inverse());
    int k = s - 1;
    while (k >= 0 && qa[k] == na - s + k) --k;
    if (k < 0) break;
    ++qa[k];
    for (int j = k + 1; j < s; ++j) qa[j] = qa[j - 1] + 1;
  }
  // ordered s-tuples of distinct points of B; a similarity's frame of two points keeps the orientation,
  // so mirror images get the mirrored frame too (the other models' tuples include both orientations)
  std::vector<std::array<int, 4>> qbs;
  {
    std::array<int, 4> t{0, 0, 0, 0};
    long total = 1;
    for (int k = 0; k < s; ++k) total *= nb;
    for (long code = 0; code < total; ++code) {
      long c = code;
      bool distinct = true;
      for (int k = 0; k < s; ++k) {
        t[k] = static_cast<int>(c % nb), c /= nb;
        for (int j = 0; j < k && distinct; ++j) distinct = t[j] != t[k];
      }
      if (distinct) qbs.push_back(t);
    }
  }
  const int mirrors = model == ClusterModel::Similarity && allow_reflection ? 2 : 1;
  std::vector<Eigen::Vector3d> ha(static_cast<size_t>(na));
  for (int i = 0; i < na; ++i) ha[static_cast<size_t>(i)] << A(i, 0), A(i, 1), 1.0;
  std::vector<double> d;
  std::vector<std::pair<int, int>> extra;
  std::vector<int> claim(static_cast<size_t>(nb));  // -2: one of the four; else the index into extra
  std::vector<double> dist_of;                        // squared distance of each claim
  for (const std::array<int, 4>& qb : qbs)
    for (int mirror = 0; mirror < mirrors; ++mirror) {
          Eigen::Matrix3d Mb;
          if (!cluster_model_frame(model, B, qb.data(), Mb, mirror == 1)) continue;
          for (size_t u = 0; u < qas.size(); ++u) {
            const std::array<int, 4>& qa = qas[u];
            const Eigen::Matrix3d H = Mb * mais[u];
            auto in_qa = [&](int i) { return std::find(qa.begin(), qa.begin() + s, i) != qa.begin() + s; };
            ++n_tried;
            // all of A on one side of the line at infinity; orientation kept unless mirrors are allowed
            const double w0 = H.row(2).dot(ha[static_cast<size_t>(qa[0])]);
            bool torn = !(w0 != 0);
            for (int i = 0; i < na && !torn; ++i) torn = !(H.row(2).dot(ha[static_cast<size_t>(i)]) * w0 > 0);
            if (torn) continue;
            if (!allow_reflection && !(H.determinant() * w0 > 0)) continue;
            // the other points of A: nearest free point of B, each point of B given to the nearest claim
            // only (a map that squeezes A onto one point of B matches one point, not all)
            std::fill(claim.begin(), claim.end(), -1);
            for (int k = 0; k < s; ++k) claim[static_cast<size_t>(qb[k])] = -2;
            d.assign(static_cast<size_t>(s), 0.0);
            extra.clear();
            for (int i = 0; i < na; ++i) {
              if (in_qa(i)) continue;
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
            // nothing beyond the minimal set near enough to matter: not worth the statistic
            double nearest = std::numeric_limits<double>::infinity();
            for (size_t k = static_cast<size_t>(s); k < d.size(); ++k) nearest = std::min(nearest, d[k]);
            if (!(nearest < 0.5 * spacing) && d.size() > static_cast<size_t>(s)) continue;
            const Significance sig = match_significance(na, d, density, spacing, s);
            if (static_cast<int>(best.size()) == keep && !(sig.log10_tail < best.back().log10_tail)) continue;
            if (!check(H).empty()) continue;  // torn or collapsed (cluster_verdict.hpp)
            ExhaustiveHypothesis h;
            h.H = H;
            for (int k = 0; k < s; ++k) h.pairs.emplace_back(qa[k], qb[k]);
            for (size_t k = 0; k < extra.size(); ++k)
              if (d[k + static_cast<size_t>(s)] <= sig.radius) h.pairs.push_back(extra[k]);
            std::sort(h.pairs.begin(), h.pairs.end());
            h.log10_tail = sig.log10_tail;
            // one map comes from every minimal set of its matches: keep it once, from its best one
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
