// The local-mean high-pass before refinement (radiometric_highpass.hpp): the filter, the spread of matches
// about their own affine epipolar geometry, and the choice between candidates.
#include "tpkit/match/radiometric_highpass.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>

using namespace tpkit;

namespace {
const double kNan = std::numeric_limits<double>::quiet_NaN();

// Correspondences of two affine views over a 1000 px square: x2 = A x1 + t + parallax along the
// epipolar direction u (random, up to 20 px), plus Gaussian noise of `across` px along the normal n and
// `along` px along u; the first `outliers` rows moved 5 px along n.
Eigen::MatrixX4d affine_pair(int n_rows, double across, double along, int outliers, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(0, 1000), par(-10, 10);
  std::normal_distribution<double> g(0, 1);
  const Eigen::Vector2d u = Eigen::Vector2d(0.8, 0.6), nrm(-0.6, 0.8);
  Eigen::Matrix2d A;
  A << 0.97, 0.05, -0.04, 1.02;
  const Eigen::Vector2d t(12, -7);
  Eigen::MatrixX4d xy(n_rows, 4);
  for (int k = 0; k < n_rows; ++k) {
    const Eigen::Vector2d p(pos(rng), pos(rng));
    Eigen::Vector2d q = A * p + t + par(rng) * u + across * g(rng) * nrm + along * g(rng) * u;
    if (k < outliers) q += 5 * nrm;
    xy.row(k) << p.x(), p.y(), q.x(), q.y();
  }
  return xy;
}
}  // namespace

TEST(RadiometricHighpass, RemovesARampKeepsTextureAndNodata) {
  // a linear ramp (the slowly varying part) plus a checkerboard texture: the high-pass leaves the
  // texture's own zero-mean part away from the borders; a NaN stays NaN and does not spread
  Raster r;
  r.width = 48, r.height = 40;
  r.data.resize(static_cast<size_t>(r.width * r.height));
  for (long y = 0; y < r.height; ++y)
    for (long x = 0; x < r.width; ++x) r.at(x, y) = static_cast<float>(500 + 4 * x - 3 * y + (((x / 4) + (y / 4)) % 2 ? 10 : -10));
  Raster ramp_only = r;
  for (long y = 0; y < r.height; ++y)
    for (long x = 0; x < r.width; ++x) ramp_only.at(x, y) = static_cast<float>(500 + 4 * x - 3 * y);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  r.at(30, 20) = nan;
  highpass_raster(ramp_only, 1.5);
  highpass_raster(r, 1.5);
  EXPECT_TRUE(std::isnan(r.at(30, 20)));
  double sum = 0, sum_abs = 0;
  int n = 0;
  for (long y = 8; y < 32; ++y)
    for (long x = 8; x < 24; ++x) {
      EXPECT_NEAR(ramp_only.at(x, y), 0.0, 2e-3) << x << " " << y;  // the ramp is gone
      ASSERT_FALSE(std::isnan(r.at(x, y)));
      sum += r.at(x, y), sum_abs += std::abs(r.at(x, y)), ++n;
    }
  EXPECT_NEAR(sum / n, 0.0, 0.5);  // zero local mean
  EXPECT_GT(sum_abs / n, 3.0);     // the texture stays
  for (long y = 8; y < 32; ++y)
    for (long x = 26; x < 40; ++x) {
      if (x == 30 && y == 20) continue;
      EXPECT_FALSE(std::isnan(r.at(x, y))) << x << " " << y;
    }
  Raster same = r;
  highpass_raster(same, 0);  // sigma 0: unchanged
  for (size_t k = 0; k < r.data.size(); ++k) {
    if (std::isnan(r.data[k])) continue;
    EXPECT_EQ(same.data[k], r.data[k]);
  }
}

TEST(RadiometricHighpass, SpreadIsTheMedianDistanceAcrossTheEpipolarLines) {
  // noise across the lines: the median of |N(0, s)| is 0.6745 s; noise along them (parallax) is not seen
  EXPECT_NEAR(epipolar_spread(affine_pair(4000, 0.1, 0, 0, 1)), 0.06745, 0.004);
  EXPECT_NEAR(epipolar_spread(affine_pair(4000, 0.2, 0, 0, 2)), 0.1349, 0.008);
  EXPECT_LT(epipolar_spread(affine_pair(4000, 0, 0.3, 0, 3)), 1e-6);
  // 5% gross outliers: the refit leaves them out of the model, the median barely moves
  EXPECT_NEAR(epipolar_spread(affine_pair(4000, 0.1, 0, 200, 4)), 0.06745 * 1.05, 0.006);
  EXPECT_TRUE(std::isnan(epipolar_spread(affine_pair(7, 0.1, 0, 0, 5))));
}

TEST(RadiometricHighpass, ChoosesTheLeastSpreadBeyondTheGain) {
  auto table = [](std::map<double, double> m) { return [m](double s) { return m.at(s); }; };
  HighpassChoice c = choose_highpass(table({{0, 0.065}, {1, 0.042}, {2, 0.045}}));
  EXPECT_EQ(c.sigma, 1);
  EXPECT_DOUBLE_EQ(c.spread, 0.042);
  EXPECT_DOUBLE_EQ(c.spread_none, 0.065);
  ASSERT_EQ(c.tried.size(), 2u);
  EXPECT_DOUBLE_EQ(c.tried_spread[1], 0.045);
  // a same-date pair: filtering adds noise; and a gain under 10% is not taken
  EXPECT_EQ(choose_highpass(table({{0, 0.023}, {1, 0.027}, {2, 0.026}})).sigma, 0);
  EXPECT_EQ(choose_highpass(table({{0, 0.050}, {1, 0.046}, {2, 0.047}})).sigma, 0);
  EXPECT_EQ(choose_highpass(table({{0, 0.050}, {1, 0.040}, {2, 0.030}})).sigma, 2);
  // the search stops at the first candidate that does not improve: 2 is not tried after a poor 1
  const HighpassChoice s = choose_highpass(table({{0, 0.050}, {1, 0.049}, {2, 0.030}}));
  EXPECT_EQ(s.sigma, 0);
  EXPECT_EQ(s.tried.size(), 1u);
  // nothing to judge by: none; a candidate that cannot be judged stops the search
  EXPECT_EQ(choose_highpass(table({{0, kNan}, {1, 0.01}, {2, 0.01}})).sigma, 0);
  EXPECT_EQ(choose_highpass(table({{0, 0.05}, {1, kNan}, {2, 0.03}})).sigma, 0);
  EXPECT_EQ(choose_highpass(table({{0, 0.05}, {1, 0.03}, {2, kNan}})).sigma, 1);
}
