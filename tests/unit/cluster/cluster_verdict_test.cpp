// The verdict of cluster-homog (cluster_verdict.hpp): accepted on a true pair with partial overlap,
// rejected on unrelated clusters under a plausible map, degenerate maps refused, tiny clusters
// unverifiable; independent of the cost's trim and truncation.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "tpkit/cluster_cost.hpp"
#include "tpkit/cluster_synth.hpp"
#include "tpkit/cluster_verdict.hpp"
#include "tpkit/physical_homography.hpp"

using namespace tpkit;

namespace {
Eigen::Matrix3d truth() { return physical_homography(paper_physical_params()); }
}  // namespace

TEST(ClusterVerdict, TruePairAcceptedEvenWithExtraAndMissingPoints) {
  ClusterSynthOptions o;
  o.noise = 0.1, o.extra = 0.3, o.missing = 0.4, o.seed = 11;
  const ClusterPair cp = synth_cluster_pair(truth(), o);
  for (CostOptions co : {CostOptions{}, CostOptions{0.45, 0}, CostOptions{0, 0.5}, CostOptions{0, 0, true}}) {
    ClusterCost cost(cp.A, cp.B, co);
    VerdictOptions vo;
    vo.hypotheses = 100000;
    const Verdict v = judge_homography(cost, cp.truth, vo);
    EXPECT_TRUE(v.accepted) << v.log10_odds;
    EXPECT_TRUE(v.degenerate.empty());
    EXPECT_GE(v.inliers, 50);
    EXPECT_LT(v.expected, 10);
    EXPECT_GT(v.log10_odds, 30);
  }
}

TEST(ClusterVerdict, UnrelatedClustersRejectedUnderAPlausibleMap) {
  for (int n : {10, 100, 2000}) {
    ClusterSynthOptions a, b;
    a.n = b.n = n;
    a.seed = 1, b.seed = 2;
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    ClusterCost cost(synth_cluster_pair(I, a).A, synth_cluster_pair(I, b).A);
    const Verdict v = judge_homography(cost, I);  // same extent, same density: the map is plausible
    EXPECT_TRUE(v.degenerate.empty()) << v.degenerate;
    EXPECT_FALSE(v.accepted) << "n " << n << ": " << v.inliers << " inliers, log10 odds " << v.log10_odds;
  }
}

TEST(ClusterVerdict, DegenerateMapsRefused) {
  ClusterSynthOptions o;
  const ClusterPair cp = synth_cluster_pair(truth(), o);
  ClusterCost cost(cp.A, cp.B);
  Eigen::Matrix3d cut = Eigen::Matrix3d::Identity();
  cut.row(2) << 1.0 / 256, 0, -1;  // line at infinity x = 256 through the middle of A
  EXPECT_NE(judge_homography(cost, cut).degenerate.find("line at infinity"), std::string::npos);
  Eigen::Matrix3d squash = Eigen::Matrix3d::Identity();
  squash(0, 0) = squash(1, 1) = 1e-3;  // all of A onto a 0.5 px speck
  const Verdict v = judge_homography(cost, squash);
  EXPECT_NE(v.degenerate.find("collapses"), std::string::npos) << v.degenerate;
  EXPECT_FALSE(v.accepted);
}

TEST(ClusterVerdict, SixPointsCannotBeVerified) {
  ClusterSynthOptions o;
  o.n = 6;
  const ClusterPair cp = synth_cluster_pair(truth(), o);
  ClusterCost cost(cp.A, cp.B);
  VerdictOptions vo;
  vo.hypotheses = 10000;  // what a search from scratch tries
  const Verdict v = judge_homography(cost, cp.truth, vo);
  EXPECT_EQ(v.inliers, 6);
  EXPECT_FALSE(v.accepted) << v.log10_odds;
}
