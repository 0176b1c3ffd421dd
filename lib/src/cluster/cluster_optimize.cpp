// See cluster_optimize.hpp.
#include "tpkit/cluster/cluster_optimize.hpp"

#include <ceres/ceres.h>

#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>

#include "tpkit/cluster/cluster_exhaustive.hpp"
#include "tpkit/cluster/cluster_search.hpp"
#include "tpkit/cluster/cluster_synth.hpp"
#include "tpkit/cluster/cluster_verdict.hpp"
#include "tpkit/core/error.hpp"

namespace tpkit {

Eigen::Matrix3d normalizing_transform(const Eigen::MatrixX2d& pts) {
  Eigen::Vector2d c = pts.colwise().mean().transpose();
  double md = 0;
  for (Eigen::Index i = 0; i < pts.rows(); ++i) md += (pts.row(i).transpose() - c).norm();
  md /= std::max<double>(1, static_cast<double>(pts.rows()));
  double s = md > 0 ? std::sqrt(2.0) / md : 1.0;
  Eigen::Matrix3d T;
  T << s, 0, -s * c(0), 0, s, -s * c(1), 0, 0, 1;
  return T;
}

namespace {

using Clock = std::chrono::steady_clock;

constexpr double kEarlyAcceptOdds = 10;  // log10 odds of the verdict that end the search early

// The free parameters of one parameterization and the map to H.
struct Space {
  Parameterization param;
  Eigen::Matrix3d TA, TB, TBi;
  std::array<double, kPhysicalParamCount> base{};
  std::vector<int> free;  // physical: indices into the 20 parameters

  int size() const { return param == Parameterization::Math ? 8 : static_cast<int>(free.size()); }

  Eigen::Matrix3d H(const Eigen::VectorXd& x) const {
    if (param == Parameterization::Math) {
      Eigen::Matrix3d Hn;
      Hn << x(0), x(1), x(2), x(3), x(4), x(5), x(6), x(7), 1.0;
      return normalized_homography(TBi * Hn * TA);
    }
    auto p = base;
    for (size_t k = 0; k < free.size(); ++k) p[free[k]] = x(static_cast<Eigen::Index>(k));
    return normalized_homography(physical_homography_t(p.data()));
  }
  Eigen::VectorXd from_H(const Eigen::Matrix3d& H) const {
    Eigen::Matrix3d Hn = TB * H * TA.inverse();
    Hn /= Hn(2, 2);
    Eigen::VectorXd x(8);
    x << Hn(0, 0), Hn(0, 1), Hn(0, 2), Hn(1, 0), Hn(1, 1), Hn(1, 2), Hn(2, 0), Hn(2, 1);
    return x;
  }
  Eigen::VectorXd from_physical(const PhysicalParams& p) {
    base = p.array();
    Eigen::VectorXd x(static_cast<Eigen::Index>(free.size()));
    for (size_t k = 0; k < free.size(); ++k) x(static_cast<Eigen::Index>(k)) = base[free[k]];
    return x;
  }
  PhysicalParams physical(const Eigen::VectorXd& x) const {
    auto p = base;
    for (size_t k = 0; k < free.size(); ++k) p[free[k]] = x(static_cast<Eigen::Index>(k));
    return PhysicalParams::from_array(p.data());
  }
  // Half-range of the paper's random deformation for free parameter k.
  double paper_step(int k) const {
    if (param == Parameterization::Math) return 0.05;
    int i = free[k] % kViewParamCount;
    switch (i) {
      case 0: case 1: case 2: return 1.0;                     // metres
      case 3: case 4: case 5: case 7: return M_PI / 10;       // radians
      case 6: return 0.01 * base[free[k]];                    // 1 % of res
      default: return 1.0;                                    // pixels
    }
  }
  // Initial standard deviation of the evolution strategy for free parameter k.
  double es_step(int k) const {
    if (param == Parameterization::Math) return 0.02;
    int v = free[k] / kViewParamCount, i = free[k] % kViewParamCount;
    double res = base[v * kViewParamCount + 6];
    switch (i) {
      case 0: case 1: return 5 * res;
      case 2: return 1e-3 * base[free[k]];
      case 3: case 4: case 5: return 0.05;
      case 7: return 0.01;
      case 6: return 0.01 * base[free[k]];
      default: return 2.0;
    }
  }
  // Physical parameters must stay a camera looking down (see physical_params_problem).
  bool valid(const Eigen::VectorXd& x) const {
    if (param == Parameterization::Math) return x.allFinite();
    return physical_params_problem(physical(x)).empty();
  }
};

std::vector<int> subset(Eigen::Index n, int max, std::mt19937_64& rng) {
  std::vector<int> idx(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) idx[static_cast<size_t>(i)] = static_cast<int>(i);
  if (n > max) {
    std::shuffle(idx.begin(), idx.end(), rng);
    idx.resize(static_cast<size_t>(max));
    std::sort(idx.begin(), idx.end());
  }
  return idx;
}

struct PairResidual {
  double ax, ay, bx, by, inv_scale;  // normalized coordinates; inv_scale turns them into pixels of B
  template <class T>
  bool operator()(const T* h, T* r) const {
    T w = h[6] * ax + h[7] * ay + T(1);
    r[0] = ((h[0] * ax + h[1] * ay + h[2]) / w - bx) * inv_scale;
    r[1] = ((h[3] * ax + h[4] * ay + h[5]) / w - by) * inv_scale;
    return true;
  }
};

// The pair fits' solve: Levenberg-Marquardt, dense QR (8 unknowns), 25 iterations, one thread, silent.
void solve_pairs(ceres::Problem& problem) {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = 25;
  o.num_threads = 1;
  o.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(o, &problem, &summary);
}

}  // namespace

Eigen::Matrix3d fit_on_pairs(const ClusterCost& cost, const Eigen::Matrix3d& H0, const std::vector<std::pair<int, int>>& pairs) {
  const Eigen::MatrixX2d &A = cost.a(), &B = cost.b();
  const Eigen::Matrix3d TA = normalizing_transform(A), TB = normalizing_transform(B), TBi = TB.inverse();
  const double kB = TB(0, 0);
  if (pairs.size() < 4) return H0;
  Eigen::Matrix3d Hn = TB * H0 * TA.inverse();
  if (!(std::abs(Hn(2, 2)) > 1e-12)) return H0;
  Hn /= Hn(2, 2);
  double h[8] = {Hn(0, 0), Hn(0, 1), Hn(0, 2), Hn(1, 0), Hn(1, 1), Hn(1, 2), Hn(2, 0), Hn(2, 1)};
  ceres::Problem problem;
  for (const auto& [i, j] : pairs) {
    const double ax = TA(0, 0) * A(i, 0) + TA(0, 2), ay = TA(1, 1) * A(i, 1) + TA(1, 2);
    const double bx = TB(0, 0) * B(j, 0) + TB(0, 2), by = TB(1, 1) * B(j, 1) + TB(1, 2);
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PairResidual, 2, 8>(new PairResidual{ax, ay, bx, by, 1.0 / kB}),
                             nullptr, h);
  }
  solve_pairs(problem);
  Hn << h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], 1.0;
  const Eigen::Matrix3d H = normalized_homography(TBi * Hn * TA);
  return H.allFinite() ? H : H0;
}

Eigen::Matrix3d polish_on_mutual_pairs(const ClusterCost& cost, const Eigen::Matrix3d& H0, int max_rounds) {
  Eigen::Matrix3d H = H0;
  std::vector<std::pair<int, int>> prev;
  for (int round = 0; round < max_rounds; ++round) {
    const std::vector<MutualPair> mutual = mutual_pairs(cost, H);
    if (mutual.size() < 8) break;
    // inliers: within 3 robust sigmas of the mutual distances (the unmatched points' pairs lie far out)
    std::vector<double> ds;
    for (const MutualPair& mp : mutual) ds.push_back(mp.d);
    std::nth_element(ds.begin(), ds.begin() + ds.size() / 2, ds.end());
    const double gate = std::max(3 * 1.4826 * ds[ds.size() / 2], 1e-3);
    std::vector<std::pair<int, int>> key;
    for (const MutualPair& mp : mutual)
      if (mp.d <= gate) key.emplace_back(mp.ia, mp.ib);
    if (key.size() < 8 || key == prev) break;
    prev = key;
    H = fit_on_pairs(cost, H, key);
  }
  return H;
}

Eigen::Matrix3d refine_on_pairs(const ClusterCost& cost, const Eigen::Matrix3d& H0, int max_rounds, int* rounds,
                                const RefineRegion* region) {
  const Eigen::MatrixX2d &A = cost.a(), &B = cost.b();
  Eigen::Matrix3d TA = normalizing_transform(A), TB = normalizing_transform(B);
  Eigen::Matrix3d TBi = TB.inverse();
  double kB = TB(0, 0);
  Eigen::MatrixX2d An(A.rows(), 2), Bn(B.rows(), 2);
  for (Eigen::Index i = 0; i < A.rows(); ++i) An.row(i) << TA(0, 0) * A(i, 0) + TA(0, 2), TA(1, 1) * A(i, 1) + TA(1, 2);
  for (Eigen::Index j = 0; j < B.rows(); ++j) Bn.row(j) << TB(0, 0) * B(j, 0) + TB(0, 2), TB(1, 1) * B(j, 1) + TB(1, 2);
  Eigen::Matrix3d H = H0, best = H0;
  double best_cost = cost(H0);
  std::vector<std::pair<long long, bool>> prev;
  int r = 0;
  for (; r < max_rounds; ++r) {
    std::vector<NnPair> pairs;
    if (region) {
      // Only the pairs whose A point lies in the region: forward queries from A points in it, backward
      // queries from B points whose image under H^-1 falls in it (the others cannot pair inside).
      double r2 = region->radius * region->radius;
      Eigen::FullPivLU<Eigen::Matrix3d> lu(H);
      if (!lu.isInvertible()) break;
      Eigen::Matrix3d Hi = lu.inverse();
      // The region tests go in index order; the queries of a large region in the KD-tree order (cache-
      // friendly: see ClusterCost::order_a), those of a small one in index order (they are close anyway).
      // Either way each pair is kept at its index and written in index order.
      double q[2], d2;
      std::vector<int> nn(static_cast<size_t>(std::max(A.rows(), B.rows())), -1);
      std::vector<double> dd(nn.size());
      std::vector<char> in(nn.size(), 0);
      size_t k = 0;
      for (Eigen::Index i = 0; i < A.rows(); ++i)
        if (!((A.row(i).transpose() - region->center).squaredNorm() > r2)) in[static_cast<size_t>(i)] = 1, ++k;
      auto forward = [&](int i) {
        Eigen::Vector3d m = H * Eigen::Vector3d(A(i, 0), A(i, 1), 1.0);
        q[0] = m(0) / m(2), q[1] = m(1) / m(2);
        if (!std::isfinite(q[0]) || !std::isfinite(q[1])) return;
        nn[static_cast<size_t>(i)] = cost.nearest_b(q, &d2);
        dd[static_cast<size_t>(i)] = std::sqrt(d2);
      };
      if (8 * k > static_cast<size_t>(A.rows())) {
        for (int i : cost.order_a())
          if (in[static_cast<size_t>(i)]) forward(i);
      } else {
        for (Eigen::Index i = 0; i < A.rows(); ++i)
          if (in[static_cast<size_t>(i)]) forward(static_cast<int>(i));
      }
      for (Eigen::Index i = 0; i < A.rows(); ++i)
        if (nn[static_cast<size_t>(i)] >= 0) pairs.push_back({static_cast<int>(i), nn[static_cast<size_t>(i)], dd[static_cast<size_t>(i)], true});
      std::fill(nn.begin(), nn.end(), -1);
      std::fill(in.begin(), in.end(), 0);
      std::vector<double> qb(static_cast<size_t>(2 * B.rows()));
      k = 0;
      for (Eigen::Index j = 0; j < B.rows(); ++j) {
        Eigen::Vector3d m = Hi * Eigen::Vector3d(B(j, 0), B(j, 1), 1.0);
        q[0] = m(0) / m(2), q[1] = m(1) / m(2);
        if (!std::isfinite(q[0]) || !std::isfinite(q[1])) continue;
        if ((Eigen::Vector2d(q[0], q[1]) - region->center).squaredNorm() > r2 * 1.5) continue;
        in[static_cast<size_t>(j)] = 1, ++k;
        qb[static_cast<size_t>(2 * j)] = q[0], qb[static_cast<size_t>(2 * j + 1)] = q[1];
      }
      auto backward = [&](int j) {
        int i = cost.nearest_a(&qb[static_cast<size_t>(2 * j)], &d2);
        if ((A.row(i).transpose() - region->center).squaredNorm() > r2) return;
        nn[static_cast<size_t>(j)] = i;
        dd[static_cast<size_t>(j)] = std::sqrt(d2);
      };
      if (8 * k > static_cast<size_t>(B.rows())) {
        for (int j : cost.order_b())
          if (in[static_cast<size_t>(j)]) backward(j);
      } else {
        for (Eigen::Index j = 0; j < B.rows(); ++j)
          if (in[static_cast<size_t>(j)]) backward(static_cast<int>(j));
      }
      for (Eigen::Index j = 0; j < B.rows(); ++j)
        if (nn[static_cast<size_t>(j)] >= 0) pairs.push_back({nn[static_cast<size_t>(j)], static_cast<int>(j), dd[static_cast<size_t>(j)], false});
    } else {
      pairs = cost.pairs(H);
    }
    if (pairs.size() < 4) break;
    std::vector<std::pair<long long, bool>> key;
    key.reserve(pairs.size());
    for (const auto& p : pairs) key.emplace_back(static_cast<long long>(p.ia) * (B.rows() + 1) + p.ib, p.forward);
    std::sort(key.begin(), key.end());
    if (key == prev) break;
    prev = key;
    std::vector<double> d;
    for (const auto& p : pairs) d.push_back(p.d);
    // the loss's scale: from the median distance, or with an unknown overlap (trim_from_data) from the
    // median of the distances the data-chosen trim keeps (the unmatched points' pairs would inflate it)
    if (cost.options().trim_from_data) d.resize(data_trim(d).keep);  // data_trim sorts d
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    double scale = std::max(1.4826 * d[d.size() / 2], 0.1);
    Eigen::Matrix3d Hn = TB * H * TA.inverse();
    if (!(std::abs(Hn(2, 2)) > 1e-12)) break;
    Hn /= Hn(2, 2);
    double h[8] = {Hn(0, 0), Hn(0, 1), Hn(0, 2), Hn(1, 0), Hn(1, 1), Hn(1, 2), Hn(2, 0), Hn(2, 1)};
    ceres::Problem::Options po;
    po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    ceres::CauchyLoss loss(scale);
    size_t stride = (pairs.size() + 2999) / 3000;
    for (size_t q = 0; q < pairs.size(); q += stride) {
      const NnPair& p = pairs[q];
      auto* f = new ceres::AutoDiffCostFunction<PairResidual, 2, 8>(
          new PairResidual{An(p.ia, 0), An(p.ia, 1), Bn(p.ib, 0), Bn(p.ib, 1), 1.0 / kB});
      problem.AddResidualBlock(f, &loss, h);
    }
    solve_pairs(problem);
    Hn << h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], 1.0;
    H = normalized_homography(TBi * Hn * TA);
    if (!H.allFinite()) break;
    if (region) {
      best = H;
      continue;
    }
    double c = cost(H);
    if (c < best_cost) best_cost = c, best = H;
  }
  if (rounds) *rounds = r + 1;
  return best;
}

GrownHypothesis refine_growing(const ClusterCost& cost, const Eigen::Matrix3d& H0, RefineRegion region, int* rounds,
                               const RegionSupport* support) {
  const Eigen::MatrixX2d& A = cost.a();
  double reach = 0;
  for (Eigen::Index i = 0; i < A.rows(); ++i) reach = std::max(reach, (A.row(i).transpose() - region.center).norm());
  Eigen::Matrix3d H = H0;
  int total = 0, r = 0, step = 0;
  region.radius = std::max(region.radius, 1e-9);
  while (region.radius < reach) {
    H = refine_on_pairs(cost, H, 4, &r, &region);
    total += r;
    if (support && ++step >= 2 && support->log10_odds(H, region.center, region.radius) < kRegionMinLog10Odds) {
      if (rounds) *rounds = total;
      return {H, false};
    }
    region.radius *= 2;
  }
  H = refine_on_pairs(cost, H, 30, &r);
  total += r;
  if (rounds) *rounds = total;
  return {H, true};
}

OptimizeResult optimize_clusters(const ClusterCost& cost, const OptimizeStart& start, const OptimizeOptions& opt) {
  auto t0 = Clock::now();
  OptimizeResult res;
  std::mt19937_64 rng(opt.seed);
  Space sp;
  sp.param = opt.param;
  sp.TA = normalizing_transform(cost.a());
  sp.TB = normalizing_transform(cost.b());
  sp.TBi = sp.TB.inverse();
  for (int v = 0; v < 2; ++v)
    for (int i = 0; i < kViewParamCount; ++i)
      if (i < 6 || opt.free_intrinsics) sp.free.push_back(v * kViewParamCount + i);

  bool have_start = start.has_physical || start.has_H;
  if (opt.param == Parameterization::Physical && !start.has_physical && opt.optimizer == OptimizerKind::Random)
    throw UsageError("the random optimizer in physical parameters needs a start: --init with physical parameters");
  if (!have_start && opt.optimizer != OptimizerKind::Default)
    throw UsageError("this optimizer needs a start (--init); only the default optimizer searches from scratch");
  // Physical parameterization without physical start: search/refine in H, express in parameters at the end.
  if (opt.param == Parameterization::Physical && !start.has_physical) sp.param = Parameterization::Math;

  Eigen::VectorXd x;
  if (have_start) {
    if (sp.param == Parameterization::Physical) {
      std::string why = physical_params_problem(start.physical);
      if (!why.empty()) throw InputError(why);
      x = sp.from_physical(start.physical);
    } else {
      Eigen::Matrix3d H0 = start.has_H ? start.H : physical_homography(start.physical);
      x = sp.from_H(H0);
    }
  }
  long evals = 0;
  auto full = [&](const Eigen::VectorXd& y) {
    ++evals;
    if (!sp.valid(y)) return std::numeric_limits<double>::infinity();
    return cost(sp.H(y));
  };

  double c = have_start ? full(x) : std::numeric_limits<double>::infinity();
  res.start_cost = c;
  Eigen::Matrix3d bestH = have_start ? sp.H(x) : Eigen::Matrix3d::Identity();
  Eigen::VectorXd bestx = x;
  double best = c;

  if (opt.optimizer == OptimizerKind::Random) {
    std::uniform_int_distribution<int> pick(0, sp.size() - 1);
    std::uniform_real_distribution<double> u(-1, 1);
    long it = 0;
    while (best > opt.target && it < opt.max_iterations) {
      ++it;
      int k = pick(rng);
      Eigen::VectorXd y = bestx;
      y(k) += u(rng) * sp.paper_step(k);
      double cy = full(y);
      if (cy < best) best = cy, bestx = y;
    }
    bestH = sp.H(bestx);
    res.iterations = it;
    res.method = "random";
  } else if (opt.optimizer == OptimizerKind::Default) {
    std::vector<int> sa = subset(cost.a().rows(), 400, rng), sb = subset(cost.b().rows(), 400, rng);
    bool sub = sa.size() < static_cast<size_t>(cost.a().rows()) || sb.size() < static_cast<size_t>(cost.b().rows());
    // Candidates that tear a cluster apart or collapse it are not answers (cluster_verdict.hpp): the
    // evolution strategy refuses them at every step, the refinements' results are checked too.
    const MapCheck map_check(cost.a(), cost.b());
    auto usable = [&](const Eigen::Matrix3d& H) { return map_check(H).empty(); };
    auto quick = [&](const Eigen::VectorXd& y) {
      ++evals;
      if (!sp.valid(y)) return std::numeric_limits<double>::infinity();
      const Eigen::Matrix3d H = sp.H(y);
      if (!usable(H)) return std::numeric_limits<double>::infinity();
      return sub ? cost.cost(H, cost.options(), &sa, &sb) : cost(H);
    };
    std::normal_distribution<double> g(0, 1);
    long budget = std::min<long>(opt.max_iterations, 3000), used = 0;
    Eigen::VectorXd xs = x;
    double cs = have_start ? quick(xs) : 0;
    // One round of (1+1)-ES from the current point, followed by the local refinement.
    auto es_round = [&](int round) {
      double s = 1.0;
      int since = 0;
      Eigen::VectorXd sig(sp.size());
      for (int k = 0; k < sp.size(); ++k) sig(k) = sp.es_step(k);
      long round_budget = 150 + 100 * round;
      for (long e = 0; e < round_budget && used < budget; ++e, ++used) {
        Eigen::VectorXd y = xs;
        for (int k = 0; k < sp.size(); ++k) y(k) += s * sig(k) * g(rng);
        double cy = quick(y);
        if (cy < cs) {
          cs = cy, xs = y, s *= 1.5, since = 0;
        } else {
          s *= 0.9;
          ++since;
        }
        if (s < 1e-3 || since > 60) break;
      }
      int rounds = 0;
      Eigen::Matrix3d Hr = refine_on_pairs(cost, sp.H(xs), 30, &rounds);
      res.local_rounds += rounds;
      double cr = cost(Hr);
      ++evals;
      if (cr < best && usable(Hr)) {
        best = cr, bestH = Hr, bestx = xs;
        res.method = "global+local";
      }
      // The next round restarts from the refined H where the parameterization allows it.
      if (sp.param == Parameterization::Math) {
        xs = sp.from_H(bestH);
        cs = quick(xs);
      }
    };
    // Sparse clusters: the cost has structure at the scale of a start's error, so the evolution strategy
    // goes first. Dense ones (> 2000 points): the cost is flat beyond the point spacing, so the search
    // goes first.
    bool dense = cost.a().rows() > 2000 || cost.b().rows() > 2000;
    if (have_start && (!dense || !opt.search_fallback)) es_round(0);
    // Done when the cost reaches the target or the verdict already accepts the best h far beyond its
    // own threshold (log10 odds >= kEarlyAcceptOdds): with unmatched points (an unknown overlap) the
    // cost of the right h stays above any fixed target, while the verdict recognizes it
    // (cluster_verdict.hpp). A marginal acceptance does not stop the search: a map right on part of
    // the clusters can pass the verdict narrowly while the search would still find the whole one.
    // The verdict on the current best, accepting at log10 odds >= min_odds.
    auto verdict_accepts = [&](double min_odds) {
      if (!std::isfinite(best)) return false;
      VerdictOptions vo;
      vo.hypotheses = std::max(1L, evals);
      vo.min_log10_odds = min_odds;
      return judge_homography(cost, bestH, vo).accepted;
    };
    bool judged = false, accepted = false;  // the early verdict on the current best (judged once per best)
    auto done = [&]() {
      if (best <= opt.target) return true;
      if (!judged && std::isfinite(best)) {
        accepted = verdict_accepts(kEarlyAcceptOdds);
        judged = true;
      }
      return accepted;
    };
    const bool small = exhaustive_hypothesis_count(cost.a().rows(), cost.b().rows()) <= kExhaustiveMaxHypotheses;
    if (small && opt.search_fallback && !(have_start && done())) {
      // Small clusters: every correspondence of four points (cluster_exhaustive.hpp), each of the best
      // fitted by least squares to its matches; the verdict picks among them.
      long tried = 0;
      const auto hyps = exhaustive_hypotheses(cost, opt.allow_reflection, 8, &tried);
      evals += tried;
      auto odds_of = [&](const Eigen::Matrix3d& H) {
        VerdictOptions vo;
        vo.hypotheses = std::max(1L, evals);
        return judge_homography(cost, H, vo).log10_odds;
      };
      double best_odds = std::isfinite(best) ? odds_of(bestH) : -std::numeric_limits<double>::infinity();
      for (const auto& hy : hyps) {
        const Eigen::Matrix3d Hr = hy.pairs.size() > 4 ? fit_on_pairs(cost, hy.H, hy.pairs) : hy.H;
        ++evals;
        if (!usable(Hr)) continue;
        const double odds = odds_of(Hr), cr = cost(Hr);
        if (odds > best_odds || (odds == best_odds && cr < best)) {
          best_odds = odds, best = cr, bestH = Hr, judged = false;
          res.method = "exhaustive+least squares";
        }
      }
    }
    // Larger ones: the quadruple search, and when its best is not accepted, a second one, wider
    // (SearchOptions::widen: in dense clusters three times the random anchors of A and B, in sparse ones
    // larger neighbourhoods): with unmatched points the quadruples whose four partners are all there
    // (around an anchor of B that was drawn) are few, and the first search can miss them all. Unrelated
    // clusters pay for both searches, less the hypotheses whose growing regions stay at chance level
    // (RegionSupport); the verdict counts every hypothesis tried.
    const RegionSupport support(cost);
    double dropped_cost = std::numeric_limits<double>::infinity();  // the best of the dropped hypotheses
    Eigen::Matrix3d dropped = Eigen::Matrix3d::Identity();
    for (int pass = 0; pass < 2 && !small && !(have_start && done()) && opt.search_fallback; ++pass) {
      if (pass == 1 && verdict_accepts(VerdictOptions{}.min_log10_odds)) break;  // at the verdict's own threshold
      SearchOptions so;
      so.seed = opt.seed + static_cast<uint64_t>(pass) * 0x9E3779B97F4A7C15ULL;
      so.allow_reflection = opt.allow_reflection;
      so.widen = pass == 0 ? 1 : 3;
      long tried = 0;
      auto hyps = search_hypotheses(cost, so, &tried);
      evals += tried;
      for (const auto& hy : hyps) {
        int rounds = 0;
        const GrownHypothesis grown = refine_growing(cost, hy.H, {hy.center, hy.radius}, &rounds, &support);
        res.local_rounds += rounds;
        const Eigen::Matrix3d& Hr = grown.H;
        double cr = cost(Hr);
        ++evals;
        if (!grown.supported) {  // its region stayed at chance level: an answer only if nothing else is
          if (cr < dropped_cost && usable(Hr)) dropped_cost = cr, dropped = Hr;
          continue;
        }
        if (cr < best && usable(Hr)) {  // a degenerate map is no candidate, however low its cost
          best = cr, bestH = Hr, judged = false;
          res.method = pass == 0 ? "search+local" : "wide search+local";
        }
        if (done()) break;
      }
    }
    for (int round = (dense && opt.search_fallback) ? 0 : 1; have_start && round < 6 && used < budget && !done(); ++round) {
      es_round(round);
      judged = false;  // a new best, perhaps
    }
    if (!std::isfinite(best) && std::isfinite(dropped_cost)) {  // every hypothesis dropped: the verdict will say no
      best = dropped_cost, bestH = dropped;
      res.method = "search+local, every hypothesis at chance level";
    }
    if (res.method.empty()) res.method = have_start ? "global+local" : "search+local";
    if (!std::isfinite(best)) throw NumericalError("no homography found: every hypothesis failed");
    // Partial overlap: the untrimmed cost stays high whatever h, so the refinement above (which keeps a
    // step only when the cost drops) can stop short of the precise map; polish on the matched points.
    if (best > opt.target) {
      const Eigen::Matrix3d Hp = polish_on_mutual_pairs(cost, bestH);
      if (usable(Hp)) bestH = Hp, best = cost(Hp), ++evals;
    }
    res.iterations = used + res.local_rounds;
  } else {
    res.method = "none";
  }
  res.H = normalized_homography(bestH);
  res.cost = best;
  res.evaluations = evals;
  res.reached_target = best <= opt.target;
  // Physical parameters of the result.
  if (opt.param == Parameterization::Physical) {
    if (sp.param == Parameterization::Physical && opt.optimizer != OptimizerKind::Default) {
      res.physical = sp.physical(bestx);
      res.has_physical = true;
    } else {
      bool fi = opt.free_intrinsics;
      std::vector<PhysicalParams> starts;
      if (sp.param == Parameterization::Physical) {
        starts.push_back(sp.physical(bestx));
      } else {
        // Nadir-looking starts: image scale ratio from the determinant of H's linear part, rotation
        // gamma2 = +-(the rotation angle of H's linear part), both tried.
        // gamma2 = -(rotation of H's linear part) first (the sign that fits eq. 4), and res1 = 20 m/px
        // (a ground footprint of km at 800 km, where a projective part like eq. 4's can be expressed).
        PhysicalParams st;
        double det = std::abs(res.H(0, 0) * res.H(1, 1) - res.H(0, 1) * res.H(1, 0));
        st.view[0].beta = st.view[1].beta = 1.4;
        double rot = std::atan2(res.H(1, 0) - res.H(0, 1), res.H(0, 0) + res.H(1, 1));
        for (double res1 : {20.0, 1.0})
          for (double sgn : {-1.0, 1.0}) {
            st.view[0].res = res1;
            st.view[1].res = det > 0 ? res1 / std::sqrt(det) : res1;
            st.view[1].gamma = sgn * rot;
            starts.push_back(st);
          }
        fi = true;
      }
      for (const PhysicalParams& st : starts) {
        double rms = 1;
        PhysicalParams fit = fit_physical_params(res.H, st, extent_grid(cost.a()), fi, &rms);
        if (rms < 0.01 && physical_params_problem(fit).empty()) {
          res.physical = fit;
          res.has_physical = true;
          break;
        }
      }
    }
  }
  res.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return res;
}

}  // namespace tpkit
