// Affine fundamental matrix: exact minimal fit, residual in pixels, RANSAC against outliers.
#include "tpkit/match/affine_fundamental.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace tpkit;

namespace {
// Two affine cameras (2x4 pixel maps of ground X, Y, Z) and n ground points; rows x1 y1 x2 y2.
Eigen::MatrixX4d affine_pairs(int n, double noise, std::mt19937& rng) {
  Eigen::Matrix<double, 2, 4> P1, P2;
  P1 << 2.0, 0.1, 0.0, 500, -0.05, -2.0, 0.8, 500;
  P2 << 1.9, 0.2, 0.3, 480, -0.1, -2.1, -0.7, 530;
  std::uniform_real_distribution<double> u(-200, 200), h(-50, 50);
  std::normal_distribution<double> g(0, noise);
  Eigen::MatrixX4d xy(n, 4);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector4d X(u(rng), u(rng), h(rng), 1);
    Eigen::Vector2d a = P1 * X, b = P2 * X;
    xy.row(i) << a.x() + g(rng), a.y() + g(rng), b.x() + g(rng), b.y() + g(rng);
  }
  return xy;
}
}  // namespace

TEST(AffineFundamental, MinimalSampleIsExact) {
  std::mt19937 rng(1);
  Eigen::MatrixX4d xy = affine_pairs(50, 0.0, rng);
  AffineFundamental F;
  ASSERT_TRUE(fit_affine_fundamental(xy, {0, 1, 2, 3}, F));
  EXPECT_NEAR(F.n.norm(), 1.0, 1e-12);
  for (int i = 0; i < 50; ++i) EXPECT_NEAR(F.residual(xy(i, 0), xy(i, 1), xy(i, 2), xy(i, 3)), 0.0, 1e-7);
  // x2^T F x1 with the 3x3 matrix is the same residual
  Eigen::Vector3d x1(xy(7, 0), xy(7, 1), 1), x2(xy(7, 2), xy(7, 3), 1);
  EXPECT_NEAR(x2.dot(F.matrix() * x1), F.residual(xy(7, 0), xy(7, 1), xy(7, 2), xy(7, 3)), 1e-9);
}

TEST(AffineFundamental, ResidualIsDistanceInPixels) {
  std::mt19937 rng(2);
  Eigen::MatrixX4d xy = affine_pairs(100, 0.0, rng);
  AffineFundamental F;
  ASSERT_TRUE(fit_affine_fundamental(xy, {}, F));
  // moving a correspondence by d along the normal in R^4 changes the residual by d
  Eigen::Vector4d p(xy(3, 2), xy(3, 3), xy(3, 0), xy(3, 1));  // (x2, y2, x1, y1) order of n
  Eigen::Vector4d q = p + 0.75 * F.n;
  EXPECT_NEAR(std::abs(F.residual(q(2), q(3), q(0), q(1))), 0.75, 1e-9);
}

TEST(AffineFundamental, DegenerateSampleRejected) {
  Eigen::MatrixX4d xy(4, 4);
  xy << 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3;  // collinear in R^4
  AffineFundamental F;
  EXPECT_FALSE(fit_affine_fundamental(xy, {}, F));
}

TEST(AffineFundamental, RansacFindsInliersAmongOutliers) {
  std::mt19937 rng(3);
  const int n = 600, bad = 240;
  Eigen::MatrixX4d xy = affine_pairs(n, 0.2, rng);
  std::uniform_real_distribution<double> u(0, 1000);
  for (int i = 0; i < bad; ++i) xy.row(i) << u(rng), u(rng), u(rng), u(rng);
  AffineFundamentalRansac o;
  o.threshold = 1.0;
  o.seed = 7;
  AffineFundamentalResult r = ransac_affine_fundamental(xy, o);
  ASSERT_TRUE(r.ok);
  int good_in = 0, bad_in = 0;
  for (int i = 0; i < n; ++i) (i < bad ? bad_in : good_in) += r.inlier[i];
  EXPECT_GE(good_in, (n - bad) * 0.97);
  EXPECT_LE(bad_in, bad * 0.01 + 3);  // a random point passes by chance only rarely
  EXPECT_LT(r.rms, 0.35);
  // deterministic for a seed
  AffineFundamentalResult r2 = ransac_affine_fundamental(xy, o);
  EXPECT_EQ(r.inlier, r2.inlier);
  EXPECT_EQ(r.F.e, r2.F.e);
}
