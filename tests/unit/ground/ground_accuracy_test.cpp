// Accuracy statistics against hand-computed values, and ENU errors against known offsets.
#include <gtest/gtest.h>

#include <cmath>

#include "tpkit/ground/ground_accuracy.hpp"

using namespace tpkit;

// 10 errors: horizontal r = 1..10 m along east, vertical |u| = 0.1 .. 1.0 m, alternating signs.
TEST(GroundAccuracy, StatisticsByHand) {
  std::vector<Eigen::Vector3d> e;
  for (int k = 1; k <= 10; ++k) e.emplace_back(k, 0, (k % 2 ? -0.1 : 0.1) * k);
  const AccuracyStats s = accuracy_stats(e);
  EXPECT_EQ(s.n, 10);
  // RMSE_e = sqrt(sum k^2 / 10) = sqrt(385 / 10)
  EXPECT_NEAR(s.rmse_e, std::sqrt(38.5), 1e-12);
  EXPECT_NEAR(s.rmse_n, 0, 1e-12);
  EXPECT_NEAR(s.rmse_r, std::sqrt(38.5), 1e-12);
  EXPECT_NEAR(s.rmse_u, std::sqrt(0.385), 1e-12);
  EXPECT_NEAR(s.mean[0], 5.5, 1e-12);
  EXPECT_NEAR(s.mean[2], 0.05, 1e-12);  // (-0.1 + 0.2 - 0.3 + ... + 1.0) / 10
  // nearest rank: ceil(0.9 * 10) = 9th smallest
  EXPECT_DOUBLE_EQ(s.ce90, 9);
  EXPECT_NEAR(s.le90, 0.9, 1e-12);
  EXPECT_NEAR(s.ce90_normal, 1.5175 * std::sqrt(38.5), 1e-12);
  EXPECT_NEAR(s.le90_normal, 1.6449 * std::sqrt(0.385), 1e-12);
}

TEST(GroundAccuracy, NearestRankQuantile) {
  EXPECT_DOUBLE_EQ(nearest_rank_quantile({3, 1, 2}, 0.9), 3);  // ceil(2.7) = 3rd
  EXPECT_DOUBLE_EQ(nearest_rank_quantile({5}, 0.9), 5);
  EXPECT_DOUBLE_EQ(nearest_rank_quantile({4, 3, 2, 1, 8, 7, 6, 5, 10, 9, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20}, 0.9), 18);
  EXPECT_TRUE(std::isnan(nearest_rank_quantile({}, 0.9)));
  EXPECT_TRUE(std::isnan(accuracy_stats({}).rmse_r));
}

// A point 3 m east, 4 m north and 2 m up of a known one (metres per degree of WGS 84 at 43.3 deg)
TEST(GroundAccuracy, EnuErrorInMetres) {
  const double lat = 43.3, rad = M_PI / 180, a = 6378137, f = 1 / 298.257223563, e2 = f * (2 - f);
  const double w = std::sqrt(1 - e2 * std::sin(lat * rad) * std::sin(lat * rad));
  const double m_lon = a / w * std::cos(lat * rad) * rad, m_lat = a * (1 - e2) / (w * w * w) * rad;
  const Eigen::Vector3d known(5.4, lat, 150), est(5.4 + 3 / m_lon, lat + 4 / m_lat, 152);
  const Eigen::Vector3d d = enu_error(est, known);
  EXPECT_NEAR(d[0], 3, 2e-3);
  EXPECT_NEAR(d[1], 4, 2e-3);
  EXPECT_NEAR(d[2], 2, 2e-3);
}
