// Optimizers on the paper's setup (section 6) with reduced trial counts: success rates of the default
// optimizer in both parameterizations, robustness to extra/missing points, the paper's random search,
// determinism. Success: cost <= 0.25 px and h within 0.5 px of the truth over the cluster's extent.
#include "tpkit/cluster/cluster_optimize.hpp"

#include <gtest/gtest.h>

#include "tpkit/cluster/cluster_synth.hpp"
#include "tpkit/core/error.hpp"

using namespace tpkit;

namespace {

struct Tally {
  int ok = 0;
  double seconds = 0;
};

Tally run(int trials, ClusterSynthOptions so, OptimizeOptions oo, CostOptions co, bool with_init) {
  Tally t;
  Eigen::Matrix3d truth = physical_homography(paper_physical_params());
  for (int k = 0; k < trials; ++k) {
    so.seed = 500 + static_cast<uint64_t>(k);
    ClusterPair cp = synth_cluster_pair(truth, so);
    ClusterCost cost(cp.A, cp.B, co);
    OptimizeStart st;
    st.has_physical = with_init;
    st.physical = paper_start_params();
    oo.seed = static_cast<uint64_t>(k + 1);
    OptimizeResult r = optimize_clusters(cost, st, oo);
    double diff = homography_max_difference(r.H, truth, extent_grid(cp.A));
    t.ok += (r.cost <= 0.25 && diff <= 0.5);
    t.seconds += r.seconds;
  }
  return t;
}
}  // namespace

TEST(ClusterOptimize, DefaultPhysicalSolvesThePaperSetup) {
  OptimizeOptions o;  // default optimizer, physical, 12 free
  Tally t = run(20, {}, o, {}, true);
  EXPECT_GE(t.ok, 20);
}

TEST(ClusterOptimize, DefaultPhysical20FreeAndMathSolveThePaperSetup) {
  OptimizeOptions o;
  o.free_intrinsics = true;
  EXPECT_GE(run(10, {}, o, {}, true).ok, 10);
  o.free_intrinsics = false;
  o.param = Parameterization::Math;
  EXPECT_GE(run(10, {}, o, {}, true).ok, 10);
}

TEST(ClusterOptimize, RobustToExtraAndMissingPoints) {
  ClusterSynthOptions so;
  so.extra = 0.2, so.missing = 0.3, so.noise = 0.1;
  OptimizeOptions o;
  EXPECT_GE(run(20, so, o, {0.45, 0}, true).ok, 19);
}

TEST(ClusterOptimize, PlainCostFailsWithExtraAndMissingPoints) {
  // The same clusters without the robust variant never reach the target: the trim is what helps.
  ClusterSynthOptions so;
  so.extra = 0.2, so.missing = 0.3, so.noise = 0.1;
  OptimizeOptions o;
  o.search_fallback = false;
  EXPECT_EQ(run(3, so, o, {}, true).ok, 0);
}

TEST(ClusterOptimize, FromScratchWithoutInit) {
  ClusterSynthOptions so;
  so.noise = 0.1;
  OptimizeOptions o;
  o.param = Parameterization::Math;
  EXPECT_GE(run(20, so, o, {0.1, 0}, false).ok, 20);
  so.extra = 0.2, so.missing = 0.3;
  EXPECT_GE(run(20, so, o, {0.45, 0}, false).ok, 18);
}

TEST(ClusterOptimize, PaperRandomSearchDecreasesTheCost) {
  // The paper's optimizer from the paper's start: the cost must fall a lot (it starts at ~110 px).
  ClusterPair cp = synth_cluster_pair(physical_homography(paper_physical_params()), {});
  ClusterCost cost(cp.A, cp.B);
  OptimizeStart st;
  st.has_physical = true;
  st.physical = paper_start_params();
  OptimizeOptions o;
  o.optimizer = OptimizerKind::Random;
  o.max_iterations = 3000;
  OptimizeResult r = optimize_clusters(cost, st, o);
  EXPECT_GT(r.start_cost, 50);
  EXPECT_LT(r.cost, r.start_cost / 5);
  EXPECT_EQ(r.iterations, 3000);
  ASSERT_TRUE(r.has_physical);
  // Its physical parameters give its H.
  EXPECT_LT(homography_max_difference(physical_homography(r.physical), r.H, extent_grid(cp.A)), 1e-6);
}

TEST(ClusterOptimize, DeterministicForASeed) {
  ClusterSynthOptions so;
  so.noise = 0.2;
  ClusterPair cp = synth_cluster_pair(physical_homography(paper_physical_params()), so);
  ClusterCost cost(cp.A, cp.B);
  OptimizeStart st;
  st.has_physical = true;
  st.physical = paper_start_params();
  for (auto kind : {OptimizerKind::Random, OptimizerKind::Default}) {
    OptimizeOptions o;
    o.optimizer = kind;
    o.max_iterations = 500;
    o.seed = 42;
    OptimizeResult a = optimize_clusters(cost, st, o), b = optimize_clusters(cost, st, o);
    EXPECT_EQ(a.H, b.H);
    EXPECT_EQ(a.iterations, b.iterations);
  }
}

TEST(ClusterOptimize, RandomNeedsAStart) {
  ClusterPair cp = synth_cluster_pair(paper_eq4_homography(), {});
  ClusterCost cost(cp.A, cp.B);
  OptimizeOptions o;
  o.optimizer = OptimizerKind::Random;
  EXPECT_THROW(optimize_clusters(cost, {}, o), UsageError);
}

// Speed (the < 20 ms and 10 000 points < 1 s goals) is measured by bench/cluster.cpp, not asserted
// here: a timed test fails on a loaded machine and proves nothing on a fast one.
TEST(ClusterOptimize, TenThousandPointsSlow) {
  ClusterSynthOptions so;
  so.n = 10000;
  so.noise = 0.1;
  OptimizeOptions o;
  Tally t = run(1, so, o, {}, true);
  EXPECT_EQ(t.ok, 1);
}
