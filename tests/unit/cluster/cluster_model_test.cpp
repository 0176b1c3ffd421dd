// The lower models of cluster-homog (cluster_model.hpp, cluster_solve.hpp): minimal solvers exact on
// their points, least squares recovering a noisy map, astroalign's TestFewSources (3 to 6 stars at
// integer positions, a 50 degree rotation and a (10, -20) shift in a 512 x 512 frame) solved as
// similarities within 1 px, 2 stars refused, unrelated few-star clusters never accepted, and the
// automatic choice keeping the homography where the map is projective.
#include "tpkit/cluster/cluster_model.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "tpkit/cluster/cluster_cost.hpp"
#include "tpkit/cluster/cluster_solve.hpp"
#include "tpkit/cluster/cluster_synth.hpp"
#include "tpkit/core/error.hpp"

using namespace tpkit;

namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector2d apply(const Eigen::Matrix3d& H, const Eigen::Vector2d& p) {
  const Eigen::Vector3d q = H * Eigen::Vector3d(p.x(), p.y(), 1);
  return q.head<2>() / q.z();
}

// astroalign's stars (reference positions before its crop of 5 px), n of them; B rotated about the frame
// centre, shifted, truncated to integers, shuffled. truth: the map including truncation's mean -0.5 px.
struct Stars {
  Eigen::MatrixX2d A, B;
  Eigen::Matrix3d truth;
};
Stars astroalign_stars(int n) {
  const double ref[6][2] = {{100, 150}, {120, 200}, {400, 200}, {400, 320}, {200, 210}, {200, 350}};
  const double a = 50 * kPi / 180;
  Eigen::Matrix3d T0, R, T1, crop, bias;
  T0 << 1, 0, -256, 0, 1, -256, 0, 0, 1;
  R << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  T1 << 1, 0, 266, 0, 1, 236, 0, 0, 1;
  crop << 1, 0, -5, 0, 1, -5, 0, 0, 1;
  bias << 1, 0, -0.5, 0, 1, -0.5, 0, 0, 1;
  const Eigen::Matrix3d M = T1 * R * T0;
  Stars s;
  s.truth = bias * crop * M * crop.inverse();
  s.A.resize(n, 2), s.B.resize(n, 2);
  for (int i = 0; i < n; ++i) {
    s.A.row(i) << ref[i][0] - 5, ref[i][1] - 5;
    const Eigen::Vector2d q = apply(M, Eigen::Vector2d(ref[i][0], ref[i][1]));
    s.B.row(n - 1 - i) << std::trunc(q.x()) - 5, std::trunc(q.y()) - 5;  // reversed order
  }
  return s;
}

ClusterSolution solve(const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B, double field, bool automatic = true,
                      ClusterModel model = ClusterModel::Homography) {
  ClusterCost cost(A, B, CostOptions{0, 0, true});
  SolveOptions so;
  so.optimize.param = Parameterization::Math;
  so.automatic = automatic;
  so.model = model;
  so.domain_area_b = field;
  return solve_clusters(cost, OptimizeStart{}, so);
}

}  // namespace

TEST(ClusterModel, MinimalFramesAreExactAndMirrorsOnlyOnRequest) {
  Eigen::Matrix3d S;  // a similarity: rotation 30 degrees, scale 1.7, shift
  const double c = 1.7 * std::cos(kPi / 6), s = 1.7 * std::sin(kPi / 6);
  S << c, -s, 12, s, c, -40, 0, 0, 1;
  Eigen::MatrixX2d A(4, 2), B(4, 2);
  A << 10, 20, 300, 40, 120, 260, 330, 310;
  for (int i = 0; i < 4; ++i) B.row(i) = apply(S, A.row(i).transpose()).transpose();
  const int idx[4] = {0, 1, 2, 3};
  for (ClusterModel m : {ClusterModel::Similarity, ClusterModel::Affine, ClusterModel::Homography}) {
    Eigen::Matrix3d Ma, Mb;
    ASSERT_TRUE(cluster_model_frame(m, A, idx, Ma));
    ASSERT_TRUE(cluster_model_frame(m, B, idx, Mb));
    const Eigen::Matrix3d H = Mb * Ma.inverse();
    for (int i = 0; i < 4; ++i)
      EXPECT_LT((apply(H, A.row(i).transpose()) - B.row(i).transpose()).norm(), 1e-9) << cluster_model_name(m) << " point " << i;
  }
  // the mirrored similarity frame of B reverses the orientation
  Eigen::Matrix3d Ma, Mb;
  ASSERT_TRUE(cluster_model_frame(ClusterModel::Similarity, A, idx, Ma));
  ASSERT_TRUE(cluster_model_frame(ClusterModel::Similarity, B, idx, Mb, true));
  const Eigen::Matrix3d mirror = Mb * Ma.inverse();
  EXPECT_LT(mirror.topLeftCorner(2, 2).determinant(), 0);
  // coincident or collinear points form no frame
  Eigen::MatrixX2d bad(3, 2);
  bad << 0, 0, 1, 1, 2, 2;
  Eigen::Matrix3d M;
  EXPECT_FALSE(cluster_model_frame(ClusterModel::Affine, bad, idx, M));
  bad.row(1) = bad.row(0);
  EXPECT_FALSE(cluster_model_frame(ClusterModel::Similarity, bad, idx, M));
}

TEST(ClusterModel, LeastSquaresRecoversTheMapFromNoisyPairs) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 500);
  std::normal_distribution<double> g(0, 0.1);
  Eigen::Matrix3d S, Af;
  S << 0.8 * std::cos(2.0), -0.8 * std::sin(2.0), 300, 0.8 * std::sin(2.0), 0.8 * std::cos(2.0), 100, 0, 0, 1;
  Af << 1.3, 0.2, -20, -0.1, 0.7, 55, 0, 0, 1;
  for (const auto& [m, T] : {std::make_pair(ClusterModel::Similarity, S), std::make_pair(ClusterModel::Affine, Af)}) {
    const int n = 200;
    Eigen::MatrixX2d A(n, 2), B(n, 2);
    std::vector<std::pair<int, int>> pairs;
    for (int i = 0; i < n; ++i) {
      A.row(i) << u(rng), u(rng);
      B.row(i) = apply(T, A.row(i).transpose()).transpose() + Eigen::RowVector2d(g(rng), g(rng));
      pairs.emplace_back(i, i);
    }
    ClusterCost cost(A, B);
    const Eigen::Matrix3d H = fit_cluster_model(cost, m, Eigen::Matrix3d::Identity(), pairs);
    EXPECT_LT(homography_rms_difference(H, T, extent_grid(A)), 0.05) << cluster_model_name(m);
    // from a homography's matches: the same map
    Eigen::Matrix3d H2;
    ASSERT_TRUE(fit_cluster_model_to_matches(cost, m, T, H2));
    EXPECT_LT(homography_rms_difference(H2, T, extent_grid(A)), 0.05) << cluster_model_name(m);
  }
}

TEST(ClusterModel, AstroalignFewStarsAreSimilaritiesWithinOnePixel) {
  for (int n = 3; n <= 6; ++n) {
    const Stars s = astroalign_stars(n);
    const ClusterSolution sol = solve(s.A, s.B, 512.0 * 512.0);
    EXPECT_TRUE(sol.chosen.verdict.accepted) << n << " stars: log10 odds " << sol.chosen.verdict.log10_odds;
    EXPECT_EQ(sol.chosen.model, ClusterModel::Similarity) << n << " stars";
    EXPECT_LT(homography_max_difference(sol.chosen.H, s.truth, s.A), 1.0) << n << " stars";
    EXPECT_EQ(sol.chosen.verdict.inliers, n);
  }
  // a homography cannot verify 4 of them, and 2 stars fix even a similarity with nothing left over
  const Stars four = astroalign_stars(4);
  const ClusterSolution h = solve(four.A, four.B, 512.0 * 512.0, false, ClusterModel::Homography);
  EXPECT_FALSE(h.chosen.verdict.accepted);
  EXPECT_FALSE(h.chosen.verdict.undetermined.empty());
  const Stars two = astroalign_stars(2);
  EXPECT_THROW(validate_cluster(two.A, "two", ClusterModel::Similarity), InputError);
  EXPECT_NO_THROW(validate_cluster(astroalign_stars(3).A, "three", ClusterModel::Similarity));
  EXPECT_THROW(validate_cluster(astroalign_stars(3).A, "three", ClusterModel::Affine), InputError);
}

TEST(ClusterModel, UnrelatedFewStarsAreNeverAccepted) {
  std::mt19937_64 rng(99);
  std::uniform_int_distribution<int> pix(0, 506);
  int accepted = 0, trials = 0;
  for (int n = 3; n <= 6; ++n)
    for (int t = 0; t < 150; ++t, ++trials) {
      Eigen::MatrixX2d A(n, 2), B(n, 2);
      for (int i = 0; i < n; ++i) A.row(i) << pix(rng), pix(rng), B.row(i) << pix(rng), pix(rng);
      try {
        validate_cluster(A, "A", ClusterModel::Similarity);
        validate_cluster(B, "B", ClusterModel::Similarity);
        accepted += solve(A, B, 512.0 * 512.0).chosen.verdict.accepted;
      } catch (const InputError&) {  // collinear draws
      } catch (const NumericalError&) {  // no map of any model matched anything beyond its minimal points
      }
    }
  EXPECT_EQ(accepted, 0) << "of " << trials;
}

TEST(ClusterModel, AutomaticChoiceKeepsTheHomographyOfAProjectiveMap) {
  ClusterSynthOptions so;
  so.n = 100, so.noise = 0.1, so.seed = 3;
  const ClusterPair cp = synth_cluster_pair(random_family_homography(2, 0.1, so.extent, 17), so);
  const ClusterSolution sol = solve(cp.A, cp.B, 0);
  EXPECT_TRUE(sol.chosen.verdict.accepted);
  EXPECT_EQ(sol.chosen.model, ClusterModel::Homography);
  EXPECT_LT(homography_rms_difference(sol.chosen.H, cp.truth, extent_grid(cp.A)), 0.5);
  // and a similarity of 100 points is reported as one, as precise as the homography
  const ClusterPair sim = synth_cluster_pair(random_family_homography(1, 0, so.extent, 18), so);
  const ClusterSolution s2 = solve(sim.A, sim.B, 0);
  EXPECT_TRUE(s2.chosen.verdict.accepted);
  EXPECT_EQ(s2.chosen.model, ClusterModel::Similarity);
  EXPECT_LT(homography_rms_difference(s2.chosen.H, sim.truth, extent_grid(sim.A)), 0.5);
}
