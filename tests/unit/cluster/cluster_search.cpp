// The correspondence-free search: rotations of any angle, scales 0.3-3, anisotropy and mild
// projective distortion, mirror images on request.
#include "tpkit/cluster/cluster_search.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "tpkit/cluster/cluster_optimize.hpp"
#include "tpkit/cluster/cluster_synth.hpp"
#include "tpkit/cluster/physical_homography.hpp"

using namespace tpkit;

namespace {
// Success: h within 0.5 px of the truth over A's extent and, when check_cost, cost <= 0.25 px (with a
// scale change the backward half of the cost sees the noise magnified, so scale tests check h only).
bool solves(const Eigen::Matrix3d& H, uint64_t seed, bool reflection = false, bool check_cost = true) {
  ClusterSynthOptions so;
  so.noise = 0.1;
  so.seed = seed;
  ClusterPair cp = synth_cluster_pair(H, so);
  ClusterCost cost(cp.A, cp.B, {0.1, 0});
  OptimizeOptions o;
  o.param = Parameterization::Math;
  o.allow_reflection = reflection;
  OptimizeResult r = optimize_clusters(cost, {}, o);
  double diff = homography_max_difference(r.H, cp.truth, extent_grid(cp.A));
  return (!check_cost || r.cost <= 0.25) && diff <= 0.5;
}

Eigen::Matrix3d similarity(double angle, double scale, double tx, double ty) {
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
  H.topLeftCorner<2, 2>() = scale * Eigen::Rotation2Dd(angle).toRotationMatrix();
  H(0, 2) = tx, H(1, 2) = ty;
  return H;
}
}  // namespace

TEST(ClusterSearch, AnyRotationAndScale) {
  int k = 0;
  for (double angle = 0; angle < 6.28; angle += M_PI / 4)
    for (double scale : {0.3, 1.0, 3.0}) {
      EXPECT_TRUE(solves(similarity(angle, scale, 300, -200), static_cast<uint64_t>(++k), false, false))
          << "angle " << angle << " scale " << scale;
    }
}

TEST(ClusterSearch, AnisotropicProjective) {
  // Eq. 4 (~90 degree rotation, anisotropic scale, mild projective part) composed with extra rotations.
  for (int k = 0; k < 6; ++k) {
    Eigen::Matrix3d H = similarity(k * 1.1, 1.0, 50, 80) * paper_eq4_homography();
    EXPECT_TRUE(solves(H, static_cast<uint64_t>(100 + k))) << k;
  }
}

TEST(ClusterSearch, MirrorOnlyWhenAllowed) {
  Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
  M(0, 0) = -1;
  Eigen::Matrix3d H = M * similarity(0.7, 1.5, 10, 20);
  EXPECT_TRUE(solves(H, 7, true));
  EXPECT_FALSE(solves(H, 7, false));
}

TEST(ClusterSearch, TrueHypothesisRanksFirst) {
  ClusterSynthOptions so;
  so.noise = 0.1;
  ClusterPair cp = synth_cluster_pair(paper_eq4_homography(), so);
  ClusterCost cost(cp.A, cp.B);
  long tried = 0;
  auto hyps = search_hypotheses(cost, {}, &tried);
  ASSERT_FALSE(hyps.empty());
  EXPECT_GT(tried, 10);
  // The best hypothesis is already close (affine approximation): within a few pixels over the extent.
  EXPECT_LT(homography_max_difference(hyps.front().H, cp.truth, extent_grid(cp.A)), 15.0);
}
