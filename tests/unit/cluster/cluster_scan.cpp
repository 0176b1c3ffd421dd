// Cost profiles (figures 2 and 5) and the mutual pairs.
#include "tpkit/cluster/cluster_scan.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "tpkit/cluster/cluster_synth.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/text_table.hpp"

using namespace tpkit;

namespace {
double argmin(const std::vector<ScanRow>& rows) {
  return std::min_element(rows.begin(), rows.end(), [](const ScanRow& a, const ScanRow& b) { return a.cost < b.cost; })
      ->value;
}
}  // namespace

TEST(ClusterScan, PhysicalAndMathProfilesHaveTheirMinimumAtTheTruth) {
  PhysicalParams p = paper_physical_params();
  ClusterPair cp = synth_cluster_pair(physical_homography(p), {});
  ClusterCost cost(cp.A, cp.B);
  auto a1 = scan_cost(cost, "alpha1", cp.truth, &p, 1.4, 1.74, 69);
  ASSERT_EQ(a1.size(), 69u);
  EXPECT_NEAR(argmin(a1), 1.57, 0.0026);
  EXPECT_LT(std::min_element(a1.begin(), a1.end(), [](auto& a, auto& b) { return a.cost < b.cost; })->cost, 1e-6);
  auto h21 = scan_cost(cost, "h21", cp.truth, nullptr, -1.0, -0.8, 81);
  EXPECT_NEAR(argmin(h21), normalized_homography(cp.truth)(1, 0), 0.0026);
  // The paper's figure 2(c): h31 has many more local minima than alpha1 (figure 5(a)).
  auto h31 = scan_cost(cost, "h31", cp.truth, nullptr, -1e-4, 1e-4, 401);
  auto minima = [](const std::vector<ScanRow>& r) {
    int m = 0;
    for (size_t i = 1; i + 1 < r.size(); ++i) m += r[i].cost < r[i - 1].cost && r[i].cost < r[i + 1].cost;
    return m;
  };
  EXPECT_NEAR(argmin(h31), normalized_homography(cp.truth)(2, 0), 1e-6);
  // Over a range where the line at infinity crosses the cluster: peaks and many local minima.
  auto h31w = scan_cost(cost, "h31", cp.truth, nullptr, -0.01, 0.01, 2001);
  auto a1w = scan_cost(cost, "alpha1", cp.truth, &p, 0.5, 2.6, 1001);
  EXPECT_GE(minima(h31w), 10);
  EXPECT_LE(minima(a1w), 3);
}

TEST(ClusterScan, BadRequests) {
  ClusterPair cp = synth_cluster_pair(paper_eq4_homography(), {});
  ClusterCost cost(cp.A, cp.B);
  PhysicalParams p = paper_physical_params();
  EXPECT_THROW(scan_cost(cost, "colour", cp.truth, &p, 0, 1, 10), UsageError);
  EXPECT_THROW(scan_cost(cost, "alpha1", cp.truth, nullptr, 0, 1, 10), UsageError);
  EXPECT_THROW(scan_cost(cost, "h11", cp.truth, nullptr, 1, 0, 10), UsageError);
  EXPECT_THROW(scan_cost(cost, "h11", cp.truth, nullptr, 0, 1, 1), UsageError);
  // Impossible cameras are left out: beta1 beyond pi/2.
  auto rows = scan_cost(cost, "beta1", cp.truth, &p, 1.0, 2.0, 11);
  for (const auto& r : rows) EXPECT_LE(r.value, M_PI / 2);
}

TEST(ClusterScan, MutualPairsAreTheTrueCorrespondences) {
  ClusterSynthOptions o;
  o.noise = 0.05;
  ClusterPair cp = synth_cluster_pair(paper_eq4_homography(), o);
  ClusterCost cost(cp.A, cp.B);
  auto pairs = mutual_pairs(cost, cp.truth);
  EXPECT_GE(pairs.size(), 98u);
  for (const auto& p : pairs) {
    Eigen::Vector3d q = cp.truth * Eigen::Vector3d(cp.A(p.ia, 0), cp.A(p.ia, 1), 1);
    EXPECT_NEAR((q.head<2>() / q(2) - cp.B.row(p.ib).transpose()).norm(), p.d, 1e-9);
    EXPECT_LT(p.d, 0.5);
  }
  std::string path = ::testing::TempDir() + "/cluster_pairs.txt";
  save_pairs(path, cost, pairs, {}, {{"seed", "1"}});
  ReadOptions ro;
  ro.kind = "pairs";
  TextTable t = read_table_file(path, ro);
  EXPECT_EQ(t.kind, "pairs");
  EXPECT_EQ(t.columns, (std::vector<std::string>{"x1", "y1", "x2", "y2", "d"}));
  EXPECT_EQ(t.rows.size(), pairs.size());
  std::remove(path.c_str());
}
