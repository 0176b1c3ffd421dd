// The KD-tree cost of eq. 3 against a brute-force O(n m) evaluation, its robust variants, the
// nearest-neighbour pairs and the cluster checks.
#include "tpkit/cluster/cluster_cost.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "tpkit/cluster/cluster_synth.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/cluster/physical_homography.hpp"

using namespace tpkit;

namespace {
Eigen::Vector2d apply(const Eigen::Matrix3d& H, const Eigen::Vector2d& p) {
  Eigen::Vector3d q = H * Eigen::Vector3d(p(0), p(1), 1);
  return q.head<2>() / q(2);
}
std::vector<double> brute_dist(const Eigen::Matrix3d& H, const Eigen::MatrixX2d& P, const Eigen::MatrixX2d& Q) {
  std::vector<double> d;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    Eigen::Vector2d m = apply(H, P.row(i).transpose());
    double best = 1e300;
    for (Eigen::Index j = 0; j < Q.rows(); ++j) best = std::min(best, (m - Q.row(j).transpose()).norm());
    d.push_back(best);
  }
  return d;
}
double robust(std::vector<double> d, double trim, double trunc) {
  if (trunc > 0)
    for (double& x : d) x = std::min(x, trunc);
  std::sort(d.begin(), d.end());
  size_t keep = std::max<size_t>(1, static_cast<size_t>(std::ceil((1 - trim) * d.size())));
  double s = 0;
  for (size_t i = 0; i < keep; ++i) s += d[i];
  return s / keep;
}
double brute_cost(const Eigen::Matrix3d& H, const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B, double trim = 0,
                  double trunc = 0) {
  return robust(brute_dist(H, A, B), trim, trunc) + robust(brute_dist(H.inverse(), B, A), trim, trunc);
}
}  // namespace

TEST(ClusterCost, ZeroAtTruthForExactClusters) {
  ClusterSynthOptions o;
  ClusterPair cp = synth_cluster_pair(paper_eq4_homography(), o);
  ClusterCost cost(cp.A, cp.B);
  EXPECT_LT(cost(cp.truth), 1e-9);
  EXPECT_GT(cost(Eigen::Matrix3d::Identity()), 10.0);
}

TEST(ClusterCost, MatchesBruteForceEq3AndRobustVariants) {
  ClusterSynthOptions o;
  o.noise = 0.5;
  o.extra = 0.2;
  o.missing = 0.3;
  ClusterPair cp = synth_cluster_pair(paper_eq4_homography(), o);
  Eigen::Matrix3d H = cp.truth;
  H(0, 2) += 7;
  H(1, 0) += 0.01;
  ClusterCost plain(cp.A, cp.B);
  EXPECT_NEAR(plain(H), brute_cost(H, cp.A, cp.B), 1e-9);
  ClusterCost trimmed(cp.A, cp.B, {0.3, 0});
  EXPECT_NEAR(trimmed(H), brute_cost(H, cp.A, cp.B, 0.3, 0), 1e-9);
  ClusterCost trunc(cp.A, cp.B, {0, 2.0});
  EXPECT_NEAR(trunc(H), brute_cost(H, cp.A, cp.B, 0, 2.0), 1e-9);
  EXPECT_LT(trimmed(H), plain(H));
}

TEST(ClusterCost, PairsAreNearestNeighboursBothWays) {
  ClusterSynthOptions o;
  o.n = 50;
  o.noise = 0.1;
  ClusterPair cp = synth_cluster_pair(paper_eq4_homography(), o);
  ClusterCost cost(cp.A, cp.B);
  auto pairs = cost.pairs(cp.truth);
  ASSERT_EQ(pairs.size(), 100u);
  auto fwd = brute_dist(cp.truth, cp.A, cp.B);
  for (const auto& p : pairs) {
    if (p.forward) {
      EXPECT_NEAR(p.d, fwd[p.ia], 1e-12);
    }
  }
}

TEST(ClusterCost, SingularHomographyCostsInfinity) {
  ClusterPair cp = synth_cluster_pair(paper_eq4_homography(), {});
  ClusterCost cost(cp.A, cp.B);
  EXPECT_TRUE(std::isinf(cost(Eigen::Matrix3d::Zero())));
}

TEST(ClusterCost, RejectsUnusableClusters) {
  Eigen::MatrixX2d one(1, 2);
  one << 1, 2;
  EXPECT_THROW(validate_cluster(one, "one"), InputError);
  Eigen::MatrixX2d line(10, 2);
  for (int i = 0; i < 10; ++i) line.row(i) << 3.0 * i + 1, 2.0 * i - 5;
  EXPECT_THROW(validate_cluster(line, "line"), InputError);
  Eigen::MatrixX2d nan = Eigen::MatrixX2d::Random(10, 2);
  nan(3, 1) = std::nan("");
  EXPECT_THROW(validate_cluster(nan, "nan"), InputError);
  EXPECT_NO_THROW(validate_cluster(Eigen::MatrixX2d::Random(10, 2), "ok"));
  EXPECT_THROW(ClusterCost(Eigen::MatrixX2d(0, 2), one), InputError);
}
