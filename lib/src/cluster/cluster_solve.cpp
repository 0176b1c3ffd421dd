// See cluster_solve.hpp.
#include "tpkit/cluster/cluster_solve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tpkit/cluster/cluster_exhaustive.hpp"
#include "tpkit/cluster/cluster_model.hpp"
#include "tpkit/cluster/physical_homography.hpp"
#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {

// A candidate of a lower model and how it was found, before the verdicts (which need the total count).
struct Proposal {
  ClusterModel model;
  Eigen::Matrix3d H;
  std::string method;
};

bool small_for(ClusterModel m, long na, long nb) {
  const long count = exhaustive_hypothesis_count(na, nb, m);
  return count > 0 && static_cast<double>(count) * static_cast<double>(na) * static_cast<double>(nb) <= kLowModelExhaustiveWork;
}

// Stage 1: the homography's search, where it is wanted or where a lower model needs its matches.
bool run_homography(const ClusterCost& cost, const SolveOptions& opt) {
  const long na = cost.a().rows(), nb = cost.b().rows();
  if (na < 4 || nb < 4) return false;
  if (opt.automatic || opt.model == ClusterModel::Homography) return true;
  return !small_for(opt.model, na, nb);
}

// Stage 2: the lower model's proposals: its exhaustive search (small clusters) and its fit to the
// homography's matches.
void propose_lower(const ClusterCost& cost, ClusterModel m, const ClusterSolution& sol, const SolveOptions& opt,
                   std::vector<Proposal>& out, long& hypotheses) {
  const long na = cost.a().rows(), nb = cost.b().rows();
  const MapCheck check(cost.a(), cost.b());
  if (small_for(m, na, nb)) {
    long tried = 0;
    const auto hyps = exhaustive_hypotheses(cost, opt.optimize.allow_reflection, 8, &tried, m);
    hypotheses += tried;
    for (const ExhaustiveHypothesis& hy : hyps) {
      const bool over = static_cast<int>(hy.pairs.size()) > cluster_model_points(m);
      const Eigen::Matrix3d H = normalized_homography(over ? fit_cluster_model(cost, m, hy.H, hy.pairs) : hy.H);
      ++hypotheses;
      if (check(H).empty()) out.push_back({m, H, over ? "exhaustive+least squares" : "exhaustive"});
    }
  }
  if (sol.has_homography_search) {
    Eigen::Matrix3d H;
    if (fit_cluster_model_to_matches(cost, m, sol.search.H, H)) {
      ++hypotheses;
      if (check(H).empty()) out.push_back({m, H, "fitted to the homography's matches"});
    }
  }
}

// P(F' > f) for F' ~ F(d1, d2) with d1 = 2 m and d2 = 2 n even: the regularized incomplete beta
// I_x(n, m) = sum_{j < m} C(n + j - 1, j) x^n (1 - x)^j, x = d2 / (d2 + d1 f), in closed form.
double f_survival_even(double f, int d1, int d2) {
  if (!(f > 0)) return 1;
  const int m = d1 / 2, n = d2 / 2;
  const double x = d2 / (d2 + d1 * f);
  double term = std::pow(x, n), sum = term;
  for (int j = 1; j < m; ++j) term *= (n + j - 1.0) / j * (1 - x), sum += term;
  return std::min(1.0, sum);
}

// The nested test of a lower candidate against a richer one on the richer one's matches (mutual nearest
// neighbours within its verdict radius): both models fitted to those pairs by least squares, and the
// chance that the richer model's smaller residuals come from its extra parameters alone,
// P(F' > F), F = ((RSS_low - RSS_rich) / d1) / (RSS_rich / d2), d1 = 2 (s_rich - s_low), d2 = 2 k - 2 s_rich.
// 1 when the richer one fits no more than its minimal points (nothing to test).
double nested_p_value(const ClusterCost& cost, const ModelCandidate& lo, const ModelCandidate& hi) {
  const int s_lo = cluster_model_points(lo.model), s_hi = cluster_model_points(hi.model);
  std::vector<std::pair<int, int>> pairs;
  for (const MutualPair& mp : mutual_pairs(cost, hi.H))
    if (mp.d <= hi.verdict.radius_px * (1 + 1e-9)) pairs.emplace_back(mp.ia, mp.ib);
  const int k = static_cast<int>(pairs.size()), d1 = 2 * (s_hi - s_lo), d2 = 2 * k - 2 * s_hi;
  if (d2 <= 0 || d1 <= 0) return 1;
  auto rss = [&](const Eigen::Matrix3d& H) {
    double sum = 0;
    for (const auto& [i, j] : pairs) {
      const Eigen::Vector3d q = H * Eigen::Vector3d(cost.a()(i, 0), cost.a()(i, 1), 1);
      sum += (q.head<2>() / q.z() - cost.b().row(j).transpose()).squaredNorm();
    }
    return sum;
  };
  const double r_lo = rss(fit_cluster_model(cost, lo.model, lo.H, pairs)), r_hi = rss(fit_cluster_model(cost, hi.model, hi.H, pairs));
  if (!std::isfinite(r_lo)) return 0;
  if (!(r_hi > 0)) return r_lo > 0 ? 0 : 1;
  return f_survival_even(((r_lo - r_hi) / d1) / (r_hi / d2), d1, d2);
}

// Stage 3: the choice among the judged candidates (see the header).
size_t choose(const ClusterCost& cost, const std::vector<ModelCandidate>& c, bool automatic, ClusterModel model) {
  auto eligible = [&](const ModelCandidate& e) { return automatic || e.model == model; };
  size_t pick = c.size();
  for (size_t i = 0; i < c.size() && pick == c.size(); ++i) {  // fewest parameters first
    if (!eligible(c[i]) || !c[i].verdict.accepted) continue;
    // against every richer candidate that is not degenerate, accepted or not: a homography rejected on
    // 5 points still shows a lower model that only approximates the map
    bool as_good = true;
    for (size_t j = i + 1; j < c.size() && as_good; ++j)
      if (eligible(c[j]) && c[j].verdict.degenerate.empty())
        as_good = c[i].verdict.inliers >= c[j].verdict.inliers && nested_p_value(cost, c[i], c[j]) >= kModelTestLevel;
    if (as_good) pick = i;
  }
  if (pick < c.size()) return pick;
  // no answer: the rejected candidate of highest odds (an accepted lower model that a rejected richer
  // one fits far better is no answer either: the map is not that model, and the richer one is not
  // verified)
  for (size_t i = 0; i < c.size(); ++i)
    if (eligible(c[i]) && !c[i].verdict.accepted && (pick == c.size() || c[i].verdict.log10_odds > c[pick].verdict.log10_odds))
      pick = i;
  return pick;
}

}  // namespace

ClusterSolution solve_clusters(const ClusterCost& cost, const OptimizeStart& start, const SolveOptions& opt) {
  ClusterSolution sol;
  std::vector<Proposal> proposals;
  if (run_homography(cost, opt)) {
    try {
      sol.search = optimize_clusters(cost, start, opt.optimize);
      sol.has_homography_search = true;
      sol.hypotheses += std::max(1L, sol.search.evaluations);
    } catch (const NumericalError&) {  // no usable homography at all: an answer only of another model
      if (!opt.automatic && opt.model == ClusterModel::Homography) throw;
    }
  }
  for (ClusterModel m : {ClusterModel::Similarity, ClusterModel::Affine})
    if (opt.automatic || opt.model == m) propose_lower(cost, m, sol, opt, proposals, sol.hypotheses);
  if (sol.has_homography_search && (opt.automatic || opt.model == ClusterModel::Homography))
    proposals.push_back({ClusterModel::Homography, sol.search.H, sol.search.method});
  if (proposals.empty())
    throw NumericalError(std::string("no ") + cluster_model_name(opt.automatic ? ClusterModel::Similarity : opt.model) +
                         " found: every hypothesis was degenerate");
  // the verdicts, every one counting all hypotheses of all models; the best of each model kept
  for (const Proposal& p : proposals) {
    VerdictOptions vo;
    // the homography is judged as cluster-homog always judged it (its own search's count); a lower model,
    // tried after it or instead of it, counts everything tried
    vo.hypotheses = p.model == ClusterModel::Homography ? std::max(1L, sol.search.evaluations) : std::max(1L, sol.hypotheses);
    vo.model = p.model;
    vo.min_log10_odds = opt.min_log10_odds;
    vo.domain_area_b = opt.domain_area_b;
    ModelCandidate c{p.model, p.H, p.method, judge_homography(cost, p.H, vo)};
    auto same = std::find_if(sol.candidates.begin(), sol.candidates.end(),
                             [&](const ModelCandidate& e) { return e.model == c.model; });
    if (same == sol.candidates.end()) sol.candidates.push_back(std::move(c));
    else if (c.verdict.log10_odds > same->verdict.log10_odds) *same = std::move(c);
  }
  const size_t pick = choose(cost, sol.candidates, opt.automatic, opt.model);
  sol.chosen = sol.candidates[pick];
  sol.cost = cost(sol.chosen.H);
  return sol;
}

}  // namespace tpkit
