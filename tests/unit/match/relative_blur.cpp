// The relative blur of two images (relative_blur.hpp): the nodata-aware Gaussian blur, and the search of
// the signed blur that maximises a score.
#include "tpkit/match/relative_blur.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace tpkit;

namespace {
Raster ramp(long w, long h) {
  Raster r;
  r.width = w, r.height = h;
  r.data.resize(static_cast<size_t>(w * h));
  for (long y = 0; y < h; ++y)
    for (long x = 0; x < w; ++x) r.at(x, y) = static_cast<float>(100 + 2 * x + 3 * y);
  return r;
}
}  // namespace

TEST(RelativeBlur, BlurKeepsALinearRampAndNodata) {
  // a Gaussian leaves a linear ramp unchanged away from the borders; a NaN stays NaN and does not spread
  Raster r = ramp(40, 30);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  r.at(20, 15) = nan;
  blur_raster(r, 1.5);
  EXPECT_TRUE(std::isnan(r.at(20, 15)));
  for (long y = 8; y < 22; ++y)
    for (long x = 8; x < 32; ++x) {
      if (x == 20 && y == 15) continue;
      ASSERT_FALSE(std::isnan(r.at(x, y)));
      // next to the hole the weights are lopsided, so the ramp shifts by a fraction of its slope at most
      const double tol = (std::abs(x - 20) <= 5 && std::abs(y - 15) <= 5) ? 1.0 : 1e-3;
      EXPECT_NEAR(r.at(x, y), 100 + 2 * x + 3 * y, tol) << x << " " << y;
    }
}

TEST(RelativeBlur, BlurSmoothsAnEdgeByItsSigma) {
  // a step edge blurred by sigma: the 16%-84% width is 2 sigma
  Raster r;
  r.width = 64, r.height = 8;
  r.data.assign(64 * 8, 0.f);
  for (long y = 0; y < 8; ++y)
    for (long x = 32; x < 64; ++x) r.at(x, y) = 1.f;
  blur_raster(r, 2.0);
  // erf: the value at x is Phi((x - 31.5) / sigma)
  for (long x = 24; x < 40; ++x) EXPECT_NEAR(r.at(x, 4), 0.5 * std::erfc(-(x - 31.5) / (2.0 * std::sqrt(2.0))), 0.01) << x;
}

TEST(RelativeBlur, SearchFindsThePeakOnEitherSide) {
  int calls = 0;
  auto peak = [&](double at) {
    return [&calls, at](double s) {
      ++calls;
      return 0.99 - 0.02 * (s - at) * (s - at);
    };
  };
  RelativeBlur b = estimate_relative_blur(peak(1.3));
  EXPECT_DOUBLE_EQ(b.sigma, 1.25);
  EXPECT_NEAR(b.score_none, 0.99 - 0.02 * 1.69, 1e-12);
  EXPECT_EQ(b.evaluations, calls);
  EXPECT_LE(calls, 8);
  b = estimate_relative_blur(peak(-2.0));
  EXPECT_DOUBLE_EQ(b.sigma, -2.0);
  // a gain below min_gain keeps 0 (a same-sensor pair)
  b = estimate_relative_blur(peak(0.2));
  EXPECT_DOUBLE_EQ(b.sigma, 0);
  // never beyond max_sigma
  b = estimate_relative_blur(peak(9), 3);
  EXPECT_DOUBLE_EQ(b.sigma, 3);
}
