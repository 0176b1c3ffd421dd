// The verdict of cluster-homog (cluster_verdict.hpp): accepted on a true pair with partial overlap,
// rejected on unrelated clusters under a plausible map, degenerate maps refused, six points verified at
// the radius their noise gives and four never; independent of the cost's trim and truncation; the
// binomial tail and the radius chosen from the data.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "tpkit/cluster/cluster_cost.hpp"
#include "tpkit/cluster/cluster_synth.hpp"
#include "tpkit/cluster/cluster_verdict.hpp"
#include "tpkit/cluster/physical_homography.hpp"

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

// Six points measured to 0.1 px carry two matches beyond the four any homography fits, at a radius
// the data choose (0.1-0.2 px, not a fixed fraction of the spacing): verifiable against the 5 400
// correspondences an exhaustive search of 6 and 6 points tries (cluster_exhaustive.hpp).
TEST(ClusterVerdict, SixPointsWithinTheNoiseAreVerified) {
  ClusterSynthOptions o;
  o.n = 6, o.noise = 0.1, o.seed = 4;
  const ClusterPair cp = synth_cluster_pair(truth(), o);
  ClusterCost cost(cp.A, cp.B);
  VerdictOptions vo;
  vo.hypotheses = 5400;
  const Verdict v = judge_homography(cost, cp.truth, vo);
  EXPECT_EQ(v.inliers, 6);
  EXPECT_LT(v.radius_px, 0.5);
  EXPECT_TRUE(v.accepted) << v.log10_odds;
  EXPECT_TRUE(v.undetermined.empty());
}

// Four points: every four correspondences fit exactly, so nothing is left to verify.
TEST(ClusterVerdict, FourPointsAreNeverDetermined) {
  ClusterSynthOptions o;
  o.n = 4, o.seed = 4;
  const ClusterPair cp = synth_cluster_pair(truth(), o);
  ClusterCost cost(cp.A, cp.B);
  const Verdict v = judge_homography(cost, cp.truth);
  EXPECT_FALSE(v.accepted);
  EXPECT_NE(v.undetermined.find("any 4 correspondences"), std::string::npos) << v.undetermined;
}

// The tail summed from its largest term agrees with the plain sum, in the upper and lower halves.
TEST(ClusterVerdict, BinomialTailMatchesTheDirectSum) {
  for (int n : {1, 7, 60, 900})
    for (double p : {1e-9, 1e-3, 0.05, 0.5, 0.97})
      for (int k = 0; k <= n; k += std::max(1, n / 17)) {
        long double sum = 0;
        for (int j = k; j <= n; ++j)
          sum += std::exp(std::lgamma(n + 1.0L) - std::lgamma(j + 1.0L) - std::lgamma(n - j + 1.0L) + j * std::log((long double)p) +
                          (n - j) * std::log1p(-(long double)p));
        const double direct = sum > 0 ? static_cast<double>(std::log10(sum)) : -std::numeric_limits<double>::infinity();
        const double ours = log10_binomial_tail(n, k, p);
        if (direct < -250) continue;  // below what the long double sum resolves
        EXPECT_NEAR(ours, std::min(0.0, direct), 1e-9 * std::max(1.0, std::fabs(direct))) << "n " << n << " k " << k << " p " << p;
      }
  EXPECT_EQ(log10_binomial_tail(10, 0, 0.3), 0);
  EXPECT_EQ(log10_binomial_tail(10, 11, 0.3), -std::numeric_limits<double>::infinity());
}

// The radius comes from the data: 30 matches within 0.1 px and 20 spread up to the spacing give the
// best significance at the 30th distance, with max(1, n - 4) radii counted.
TEST(ClusterVerdict, RadiusChosenWhereTheMatchesEnd) {
  std::vector<double> d;
  for (int i = 0; i < 30; ++i) d.push_back(0.003 * (i + 1));
  for (int i = 0; i < 20; ++i) d.push_back(2.0 + 0.4 * i);
  const double spacing = 10, density = 1 / (spacing * spacing);
  const Significance s = match_significance(60, d, density, spacing);
  EXPECT_EQ(s.inliers, 30);
  EXPECT_DOUBLE_EQ(s.radius, 0.09);
  EXPECT_EQ(s.radii, 56);
  EXPECT_LT(s.log10_tail, -40);
  // nothing beyond four matches: no evidence at all
  EXPECT_EQ(match_significance(4, {0.0, 0.0, 0.0, 0.0}, density, spacing).log10_tail, 0);
}
