// Least-squares matching against a known warp: a smooth random texture, image 2 = affine warp of
// image 1 with gain, offset and noise. Truth of p1 in image 2 is known in closed form.
#include "tpkit/match/lsm_refine.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <random>

#include "tpkit/match/match_pair.hpp"

using namespace tpkit;

namespace {
struct Texture {
  std::vector<std::array<double, 4>> waves;  // kx, ky, phase, amplitude
  explicit Texture(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> k(-1.2, 1.2), ph(0, 6.283);
    for (int i = 0; i < 30; ++i) waves.push_back({k(rng), k(rng), ph(rng), 1.0 / (1 + i * 0.05)});
  }
  double operator()(double x, double y) const {
    double s = 0;
    for (const auto& w : waves) s += w[3] * std::sin(w[0] * x + w[1] * y + w[2]);
    return s;
  }
};

// Renders ground texture through x_img -> ground = M (x_img - c) + g0, average of 4x4 subsamples.
Raster render(const Texture& t, long size, const Eigen::Matrix2d& M, const Eigen::Vector2d& c, double gain, double offset,
              double noise, unsigned seed) {
  Raster r;
  r.width = r.height = size;
  r.data.resize(size * size);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, noise);
  for (long y = 0; y < size; ++y)
    for (long x = 0; x < size; ++x) {
      double s = 0;
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
          Eigen::Vector2d p(x - 0.375 + 0.25 * i, y - 0.375 + 0.25 * j);
          Eigen::Vector2d q = M * (p - c);
          s += t(q.x(), q.y());
        }
      r.at(x, y) = static_cast<float>(offset + gain * s / 16 + (noise > 0 ? g(rng) : 0));
    }
  return r;
}
}  // namespace

TEST(Lsm, BicubicReproducesLinearRampAndGradient) {
  Raster r;
  r.x0 = 10;
  r.y0 = 20;
  r.width = r.height = 12;
  r.data.resize(144);
  for (long y = 0; y < 12; ++y)
    for (long x = 0; x < 12; ++x) r.at(x, y) = static_cast<float>(3 + 2 * (x + 10) - 0.5 * (y + 20));
  double v, gx, gy;
  ASSERT_TRUE(bicubic(r, 15.3, 25.7, v, &gx, &gy));
  EXPECT_NEAR(v, 3 + 2 * 15.3 - 0.5 * 25.7, 1e-4);
  EXPECT_NEAR(gx, 2.0, 1e-5);
  EXPECT_NEAR(gy, -0.5, 1e-5);
  EXPECT_FALSE(bicubic(r, 10.5, 25, v));  // needs one pixel of support on each side
}

TEST(Lsm, RecoversAffineShiftWithRadiometry) {
  Texture tex(5);
  const long S = 160;
  const Eigen::Vector2d c(80, 80);
  Eigen::Matrix2d M1 = Eigen::Matrix2d::Identity();
  // image 2: ground = M2 (x2 - c) with M2 = M1 * B^-1, i.e. x2 = c + B (x1 - c) + t
  Eigen::Matrix2d B;
  B << 1.04, 0.06, -0.03, 0.97;
  Eigen::Vector2d tshift(0.37, -0.61);
  Eigen::Matrix2d M2 = B.inverse();
  Raster I1 = render(tex, S, M1, c, 300, 1000, 3.0, 1);
  Raster I2 = render(tex, S, M2, c + tshift, 250, 700, 3.0, 2);
  LsmOptions o;
  std::vector<double> err;
  for (double px : {60.3, 75.0, 88.7, 101.2})
    for (double py : {62.1, 79.5, 95.4}) {
      Eigen::Vector2d p1(px, py), truth = c + tshift + B * (p1 - c);
      Eigen::Vector2d start = truth + Eigen::Vector2d(0.6, -0.5);
      LsmResult r = lsm_refine(I1, I2, p1, start, Eigen::Matrix2d::Identity(), o);
      ASSERT_TRUE(r.ok()) << to_string(r.status);
      err.push_back((r.p2 - truth).norm());
      EXPECT_GT(r.corr, 0.95);
      EXPECT_GT(r.sigma, 0.0);
      EXPECT_LT(r.sigma, 0.05);
      EXPECT_NEAR(r.A(0, 0), B(0, 0), 0.02);
      EXPECT_NEAR(r.A(0, 1), B(0, 1), 0.02);
    }
  std::sort(err.begin(), err.end());
  EXPECT_LT(err[err.size() / 2], 0.02);
  EXPECT_LT(err.back(), 0.05);
}

TEST(Lsm, KeypointOrientationInitialisesRotation) {
  // image 2 is image 1 rotated by +40 degrees (from +x towards +y) about c: a window that starts
  // unrotated cannot converge, the keypoint-derived initial map can.
  Texture tex(9);
  const long S = 160;
  const Eigen::Vector2d c(80, 80);
  const double a = 40 * M_PI / 180;
  Eigen::Matrix2d R;
  R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  Raster I1 = render(tex, S, Eigen::Matrix2d::Identity(), c, 300, 1000, 2.0, 3);
  Raster I2 = render(tex, S, R.inverse(), c, 300, 1000, 2.0, 4);
  Eigen::Vector2d p1(70.4, 90.2), truth = c + R * (p1 - c);
  LsmOptions o;
  Eigen::Matrix2d A0 = keypoint_affine(4.0, 10.0, 4.0, 50.0);  // OpenCV angles differ by +40 degrees
  LsmResult r = lsm_refine(I1, I2, p1, truth + Eigen::Vector2d(0.5, 0.4), A0, o);
  ASSERT_TRUE(r.ok()) << to_string(r.status);
  EXPECT_LT((r.p2 - truth).norm(), 0.03);
  EXPECT_NEAR(r.A(1, 0), std::sin(a), 0.02);
}

TEST(Lsm, DropsFlatAndFarAndNodata) {
  Raster flat;
  flat.width = flat.height = 64;
  flat.data.assign(64 * 64, 100.f);
  LsmOptions o;
  EXPECT_EQ(lsm_refine(flat, flat, {32, 32}, {32, 32}, Eigen::Matrix2d::Identity(), o).status, LsmStatus::Flat);

  Texture tex(11);
  const Eigen::Vector2d c(60, 60);
  Raster I1 = render(tex, 120, Eigen::Matrix2d::Identity(), c, 300, 1000, 1.0, 5);
  Raster I2 = render(tex, 120, Eigen::Matrix2d::Identity(), c + Eigen::Vector2d(1.2, 0.0), 300, 1000, 1.0, 6);
  // truth is 1.2 px from the start: allowed with max_shift 1.5, dropped with 0.5
  LsmResult ok = lsm_refine(I1, I2, {55, 58}, {55, 58}, Eigen::Matrix2d::Identity(), o);
  ASSERT_TRUE(ok.ok()) << to_string(ok.status);
  EXPECT_NEAR(ok.p2.x(), 56.2, 0.03);
  o.max_shift = 0.5;
  LsmResult far = lsm_refine(I1, I2, {55, 58}, {55, 58}, Eigen::Matrix2d::Identity(), o);
  EXPECT_FALSE(far.ok());
  // a NaN (nodata) pixel inside the window
  o.max_shift = 1.5;
  I2.at(57, 60) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(lsm_refine(I1, I2, {55, 58}, {55, 58}, Eigen::Matrix2d::Identity(), o).ok());
  // window leaving the image
  EXPECT_EQ(lsm_refine(I1, I2, {3, 58}, {3, 58}, Eigen::Matrix2d::Identity(), o).status, LsmStatus::OutOfImage);
}

TEST(Lsm, QuadraticStageRemovesCurvatureBias) {
  // image 2 = image 1 under a known quadratic warp x2 = c + B (x1 - c) + (0, k |x1 - c|^2): the affine
  // window estimates the window average of the warp, biased by about k x 2 taper^2 along y at the
  // centre; the quadratic stage follows it.
  Texture tex(13);
  const long S = 160;
  const Eigen::Vector2d c(80, 80);
  const double kq = 0.004;  // px^-1
  Eigen::Matrix2d B;
  B << 1.02, 0.0, -0.05, 1.1;
  auto warp = [&](const Eigen::Vector2d& x1) {
    Eigen::Vector2d d = x1 - c;
    return Eigen::Vector2d(c + B * d + Eigen::Vector2d(0, kq * d.squaredNorm()));
  };
  // render image 2 by inverting the warp per subsample (Newton), so that I2(warp(x1)) = I1(x1)
  Raster I1 = render(tex, S, Eigen::Matrix2d::Identity(), c, 300, 1000, 1.0, 7);
  Raster I2;
  I2.width = I2.height = S;
  I2.data.resize(S * S);
  std::mt19937 rng(8);
  std::normal_distribution<double> g(0, 1.0);
  for (long y = 0; y < S; ++y)
    for (long x = 0; x < S; ++x) {
      double sum = 0;
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
          Eigen::Vector2d q(x - 0.375 + 0.25 * i, y - 0.375 + 0.25 * j), p = c + B.inverse() * (q - c);
          for (int it = 0; it < 20; ++it) {
            Eigen::Vector2d d = p - c;
            Eigen::Matrix2d J = B;
            J.row(1) += Eigen::RowVector2d(2 * kq * d.x(), 2 * kq * d.y());
            p -= J.inverse() * (warp(p) - q);
          }
          sum += tex(p.x() - c.x(), p.y() - c.y());
        }
      I2.at(x, y) = static_cast<float>(900 + 280 * sum / 16 + g(rng));
    }
  LsmOptions aff;
  LsmOptions quad;
  quad.quadratic = true;
  quad.adaptive = false;
  // the same warp bends along y only: the epipolar model (3 curvature terms along y) must follow it too
  LsmOptions epi = quad;
  epi.epipolar_dir = Eigen::Vector2d(0, 2.5);
  LsmOptions measured = epi;  // tp-match's shape choice: the same refinement, the curvature's significance measured
  measured.measure_curvature = true;
  std::vector<double> ea, eq, ee, chi2;
  for (double px : {62.3, 78.0, 91.7})
    for (double py : {64.1, 80.5, 94.4}) {
      Eigen::Vector2d p1(px, py), truth = warp(p1);
      Eigen::Matrix2d J = B;
      J.row(1) += Eigen::RowVector2d(2 * kq * (px - c.x()), 2 * kq * (py - c.y()));
      LsmResult a = lsm_refine(I1, I2, p1, truth + Eigen::Vector2d(0.4, -0.3), J, aff);
      LsmResult q = lsm_refine(I1, I2, p1, truth + Eigen::Vector2d(0.4, -0.3), J, quad);
      LsmResult e = lsm_refine(I1, I2, p1, truth + Eigen::Vector2d(0.4, -0.3), J, epi);
      ASSERT_TRUE(a.ok()) << to_string(a.status);
      ASSERT_TRUE(q.ok()) << to_string(q.status);
      ASSERT_TRUE(e.ok()) << to_string(e.status);
      EXPECT_TRUE(q.quadratic);
      EXPECT_TRUE(e.quadratic);
      ea.push_back((a.p2 - truth).norm());
      eq.push_back((q.p2 - truth).norm());
      ee.push_back((e.p2 - truth).norm());
      // second derivative of y along u and v: 2 kq each
      EXPECT_NEAR(2 * q.H(3), 2 * kq, 0.002);
      EXPECT_NEAR(2 * q.H(5), 2 * kq, 0.002);
      EXPECT_NEAR(2 * e.H(3), 2 * kq, 0.002);
      EXPECT_NEAR(2 * e.H(5), 2 * kq, 0.002);
      EXPECT_EQ(e.H(0), 0.0);  // nothing across the epipolar direction
      EXPECT_EQ(e.H(2), 0.0);
      const LsmResult m = lsm_refine(I1, I2, p1, truth + Eigen::Vector2d(0.4, -0.3), J, measured);
      EXPECT_EQ(m.p2, e.p2);  // measuring changes nothing
      EXPECT_TRUE(std::isnan(e.curvature_chi2));
      chi2.push_back(m.curvature_chi2);
    }
  // a curvature of 0.004 px^-1 moves the affine window's position by tens of its standard deviations
  std::sort(chi2.begin(), chi2.end());
  EXPECT_GT(chi2.front(), 10);
  std::sort(ee.begin(), ee.end());
  EXPECT_LT(ee[ee.size() / 2], 0.015);
  EXPECT_LT(ee.back(), 0.03);
  std::sort(ea.begin(), ea.end());
  std::sort(eq.begin(), eq.end());
  EXPECT_GT(ea[ea.size() / 2], 0.04);  // the affine bias (about 2 kq taper^2 = 0.07 px less the weighting)
  EXPECT_LT(eq[eq.size() / 2], 0.015);
  EXPECT_LT(eq.back(), 0.03);
}

TEST(Lsm, CurvatureSignificanceOfAnAffineMap) {
  // image 2 an affine warp of image 1 with noise: the quadratic stage's curvature is noise, and its
  // significance (chi-square with one degree of freedom along the epipolar direction: median 0.45) stays
  // below tp-match's threshold of 2 for the quadratic model
  Texture tex(13);
  const long S = 160;
  const Eigen::Vector2d c(80, 80);
  Eigen::Matrix2d B;
  B << 1.02, 0.0, -0.05, 1.1;
  // noise 6 grey levels on a texture of gain 300: nearly noiseless, any difference between the two
  // renderings becomes significant (image 2's pixels integrate a sheared footprint of image 1's: median 4.0
  // at noise 1, 1.8 at 3, 1.2 at 6, 0.27 at 12); the real pairs of the tests come out at 0.3-0.9
  const double noise = 6;
  const Raster I1 = render(tex, S, Eigen::Matrix2d::Identity(), c, 300, 1000, noise, 7);
  const Raster I2 = render(tex, S, B.inverse(), c, 280, 900, noise, 8);
  LsmOptions o;
  o.quadratic = true;
  o.measure_curvature = true;
  o.epipolar_dir = Eigen::Vector2d(0, 1);
  std::vector<double> chi2;
  for (double px : {52.3, 62.3, 78.0, 91.7, 104.2})
    for (double py : {54.1, 64.1, 80.5, 94.4, 106.8}) {
      const Eigen::Vector2d p1(px, py), truth = c + B * (p1 - c);
      const LsmResult r = lsm_refine(I1, I2, p1, truth + Eigen::Vector2d(0.3, -0.2), B, o);
      ASSERT_TRUE(r.ok()) << to_string(r.status);
      EXPECT_LT((r.p2 - truth).norm(), 0.05);
      ASSERT_TRUE(std::isfinite(r.curvature_chi2));
      chi2.push_back(r.curvature_chi2);
    }
  std::sort(chi2.begin(), chi2.end());
  EXPECT_LT(chi2[chi2.size() / 2], 2);
}

TEST(Lsm, SupportDiscChangesLittle) {
  // only pixels within 3 taper sigmas: the same solution to well below the accuracy
  Texture tex(21);
  const Eigen::Vector2d c(80, 80);
  Raster I1 = render(tex, 160, Eigen::Matrix2d::Identity(), c, 300, 1000, 2.0, 9);
  Raster I2 = render(tex, 160, Eigen::Matrix2d::Identity(), c + Eigen::Vector2d(0.3, 0.45), 300, 1000, 2.0, 10);
  LsmOptions full, disc;
  full.support = 0;
  disc.support = 3;
  LsmResult a = lsm_refine(I1, I2, {70.2, 85.6}, {70.2, 85.6}, Eigen::Matrix2d::Identity(), full);
  LsmResult b = lsm_refine(I1, I2, {70.2, 85.6}, {70.2, 85.6}, Eigen::Matrix2d::Identity(), disc);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_LT((a.p2 - b.p2).norm(), 0.005);
  EXPECT_LT((b.p2 - Eigen::Vector2d(70.5, 86.05)).norm(), 0.03);
}

TEST(Lsm, RegionOffsetAndTightCrop) {
  // image 2 given as a region (x0, y0) a few pixels larger than the window and its interpolation
  // support: the same solution as on the whole image; a region starting at the window's first column
  // leaves no support on that side.
  Texture tex(13);
  const Eigen::Vector2d c(60, 60);
  Raster I1 = render(tex, 120, Eigen::Matrix2d::Identity(), c, 300, 1000, 1.0, 7);
  Raster I2 = render(tex, 120, Eigen::Matrix2d::Identity(), c + Eigen::Vector2d(0.4, -0.3), 300, 1000, 1.0, 8);
  LsmOptions o;
  o.support = 0;  // the whole 21 x 21 window
  const Eigen::Vector2d p1(55.2, 58.7);
  LsmResult full = lsm_refine(I1, I2, p1, p1, Eigen::Matrix2d::Identity(), o);
  ASSERT_TRUE(full.ok()) << to_string(full.status);
  auto crop = [&](long x0, long y0, long w, long h) {
    Raster r;
    r.x0 = x0, r.y0 = y0, r.width = w, r.height = h;
    r.data.resize(static_cast<size_t>(w * h));
    for (long y = 0; y < h; ++y)
      for (long x = 0; x < w; ++x) r.at(x, y) = I2.at(x0 + x, y0 + y);
    return r;
  };
  // window: p2 +- (10 + drift) px, plus the bicubic support (1 before, 2 after)
  const long x0 = 55 - 13, y0 = 58 - 13, w = 28, h = 28;
  LsmResult part = lsm_refine(I1, crop(x0, y0, w, h), p1, p1, Eigen::Matrix2d::Identity(), o);
  ASSERT_TRUE(part.ok()) << to_string(part.status);
  EXPECT_NEAR(part.p2.x(), full.p2.x(), 1e-9);
  EXPECT_NEAR(part.p2.y(), full.p2.y(), 1e-9);
  EXPECT_NEAR(part.sigma, full.sigma, 1e-9);
  EXPECT_EQ(part.iterations, full.iterations);
  // the window's first column falls on the region's first pixel: no support left of it
  EXPECT_EQ(lsm_refine(I1, crop(55 - 10, y0, w, h), p1, p1, Eigen::Matrix2d::Identity(), o).status, LsmStatus::OutOfImage);
}

// Acceptance by what the fit measures: the same window with little noise is refined; under heavy noise
// (the radiometry of image 2 barely related to image 1's) the refinement is rejected by its radiometric
// fit (low correlation) or its precision (sigma from the normal equations), never passed as refined;
// each test is the one that rejects when the other is switched off.
TEST(Lsm, RejectsByPrecisionOrFit) {
  Texture tex(17);
  const Eigen::Vector2d c(60, 60), shift(0.4, -0.3);
  const Raster I1 = render(tex, 120, Eigen::Matrix2d::Identity(), c, 300, 1000, 1.0, 5);
  const Raster clean = render(tex, 120, Eigen::Matrix2d::Identity(), c + shift, 300, 1000, 1.0, 6);
  const Raster noisy = render(tex, 120, Eigen::Matrix2d::Identity(), c + shift, 300, 1000, 2500.0, 6);
  const Eigen::Vector2d p1(57, 61);
  LsmOptions o;
  const LsmResult good = lsm_refine(I1, clean, p1, p1, Eigen::Matrix2d::Identity(), o);
  ASSERT_TRUE(good.ok()) << to_string(good.status);
  EXPECT_LT(good.sigma, 0.02);
  EXPECT_NEAR((good.p2 - (p1 + shift)).norm(), 0, 0.03);  // image 2 sees ground point g at g + c + shift
  const LsmResult bad = lsm_refine(I1, noisy, p1, p1, Eigen::Matrix2d::Identity(), o);
  EXPECT_FALSE(bad.ok());
  EXPECT_TRUE(bad.status == LsmStatus::LowCorrelation || bad.status == LsmStatus::Imprecise || bad.status == LsmStatus::Drifted)
      << to_string(bad.status) << " corr " << bad.corr << " sigma " << bad.sigma;
  // the precision alone: a moderately noisy window (correlation ~0.9) refined with a sigma bound below its sigma
  const Raster some = render(tex, 120, Eigen::Matrix2d::Identity(), c + shift, 300, 1000, 300.0, 6);
  LsmResult r = lsm_refine(I1, some, p1, p1, Eigen::Matrix2d::Identity(), o);
  ASSERT_TRUE(r.ok()) << to_string(r.status) << " corr " << r.corr << " sigma " << r.sigma;
  o.max_sigma = r.sigma * 0.5;
  EXPECT_EQ(lsm_refine(I1, some, p1, p1, Eigen::Matrix2d::Identity(), o).status, LsmStatus::Imprecise);
  // the fit alone: the same window with the correlation bound above its correlation
  o.max_sigma = 1;
  o.min_corr = std::min(0.999, r.corr + 0.01);
  EXPECT_EQ(lsm_refine(I1, some, p1, p1, Eigen::Matrix2d::Identity(), o).status, LsmStatus::LowCorrelation);
}

// The robust L1 fit where a corner of image 2's window shows something else (an occluding roof): the
// corner pulls the least-squares fit, the L1 fit keeps to the map, in a few iterations (5.3 on average).
TEST(Lsm, L1IgnoresOccludedCorner) {
  Texture tex(11), other(12);
  const long S = 160;
  const Eigen::Vector2d c(80, 80), tshift(0.42, -0.27);
  Raster I1 = render(tex, S, Eigen::Matrix2d::Identity(), c, 300, 1000, 2.0, 1);
  Raster I2 = render(tex, S, Eigen::Matrix2d::Identity(), c + tshift, 300, 1000, 2.0, 2);
  const Raster occluder = render(other, S, Eigen::Matrix2d::Identity(), c, 300, 1100, 2.0, 3);
  LsmOptions l1, l2;
  l2.l1 = false;
  std::vector<double> err, plain_err;
  double iterations = 0;
  for (double px : {50.2, 70.6, 90.3, 110.8})
    for (double py : {55.4, 80.1, 104.7}) {
      const Eigen::Vector2d p1(px, py), truth = p1 + tshift, start = truth + Eigen::Vector2d(0.5, 0.4);
      // image 2's pixels right of and below p1 + 3 px (about 20% of the support disc) show the occluder
      Raster J = I2;
      for (long y = static_cast<long>(truth.y()) + 3; y < S; ++y)
        for (long x = static_cast<long>(truth.x()) + 3; x < S; ++x) J.at(x, y) = occluder.at(x, y);
      const LsmResult r = lsm_refine(I1, J, p1, start, Eigen::Matrix2d::Identity(), l1);
      ASSERT_TRUE(r.ok()) << to_string(r.status);
      err.push_back((r.p2 - truth).norm());
      iterations += r.iterations;
      const LsmResult q = lsm_refine(I1, J, p1, start, Eigen::Matrix2d::Identity(), l2);
      plain_err.push_back(q.ok() ? (q.p2 - truth).norm() : 1.0);
    }
  std::sort(err.begin(), err.end());
  std::sort(plain_err.begin(), plain_err.end());
  EXPECT_LT(err[err.size() / 2], 0.03);                               // measured 0.024
  EXPECT_LT(err[err.size() / 2], 0.5 * plain_err[plain_err.size() / 2]);  // least squares: 0.064
  EXPECT_LT(iterations / static_cast<double>(err.size()), 8.0);
}

TEST(Lsm, BaselineAndAvx2CodeGiveTheSameResults) {
  // where the CPU has AVX2, image 2 is interpolated two pixels at a time; the baseline code one at a
  // time: the same operations lane by lane, so the same refinements to the bit, in every stage
  Texture tex(21);
  const long S = 160;
  const Eigen::Vector2d c(80, 80);
  Eigen::Matrix2d B;
  B << 1.03, 0.05, -0.04, 0.96;
  Raster I1 = render(tex, S, Eigen::Matrix2d::Identity(), c, 300, 1000, 2.0, 3);
  Raster I2 = render(tex, S, B.inverse(), c + Eigen::Vector2d(0.3, -0.4), 260, 800, 2.0, 4);
  int compared = 0;
  for (bool quadratic : {false, true})
    // two window sizes; a disc's and a window's pixel counts are odd, so the support's last pixel goes
    // through the one-pixel code, the pixels outside it (an even count) through pairs only
    for (int window : {21, 15})
      for (double px : {50.2, 77.7, 104.9})
        for (double py : {55.5, 81.3, 99.9}) {
          LsmOptions o;
          o.quadratic = quadratic;
          o.window = window;
          if (quadratic) o.epipolar_dir = Eigen::Vector2d(1, 0.2);
          const Eigen::Vector2d p1(px, py), start = c + Eigen::Vector2d(0.3, -0.4) + B * (p1 - c) + Eigen::Vector2d(0.4, 0.3);
          const LsmResult a = lsm_refine(I1, I2, p1, start, Eigen::Matrix2d::Identity(), o);
          o.baseline_code = true;
          const LsmResult b = lsm_refine(I1, I2, p1, start, Eigen::Matrix2d::Identity(), o);
          ASSERT_EQ(a.status, b.status);
          EXPECT_EQ(a.iterations, b.iterations);
          EXPECT_EQ(a.p2, b.p2);
          EXPECT_EQ(a.A, b.A);
          EXPECT_EQ(a.H, b.H);
          EXPECT_EQ(a.sigma, b.sigma);
          EXPECT_EQ(a.corr, b.corr);
          compared += a.ok();
        }
  EXPECT_GE(compared, 30);
}

// Images of two dates: a shadow (grey levels x 0.3: a change no gain and offset follow) falls on a
// patch of the window in image 1 and, the sun having moved, on another patch in image 2. The L1 fit keeps
// to the map (within 0.05 px of the truth); the whole window's correlation counts the shadows, the
// correlation over the pixels the residual mask keeps does not, and acceptance by it refines the window.
TEST(Lsm, MovedShadowResidualMask) {
  Texture tex(21);
  const long S = 160;
  const Eigen::Vector2d c(80, 80), tshift(0.31, -0.44);
  const Raster I1c = render(tex, S, Eigen::Matrix2d::Identity(), c, 300, 3000, 2.0, 1);
  const Raster I2c = render(tex, S, Eigen::Matrix2d::Identity(), c + tshift, 300, 3000, 2.0, 2);
  // a 4 x 4 px shadow whose top-left pixel is (x0, y0)
  auto shade = [](Raster r, long x0, long y0) {
    for (long y = y0; y < y0 + 4; ++y)
      for (long x = x0; x < x0 + 4; ++x) r.at(x, y) = static_cast<float>(0.3 * r.at(x, y));
    return r;
  };
  LsmOptions masked;
  masked.mask_k = 3;
  masked.min_corr = 0.97;
  LsmOptions plain = masked;
  plain.mask_k = 0;
  int n = 0;
  for (double px : {50.2, 80.6, 110.3})
    for (double py : {55.4, 80.1, 104.7}) {
      const Eigen::Vector2d p1(px, py), truth = p1 + tshift, start = truth + Eigen::Vector2d(0.6, -0.5);
      // image 1: up and left of the point (offsets -6..-3); image 2: down and right (+3..+6)
      const Raster I1 = shade(I1c, std::lround(p1.x()) - 6, std::lround(p1.y()) - 6);
      const Raster I2 = shade(I2c, std::lround(truth.x()) + 3, std::lround(truth.y()) + 3);
      const LsmResult r = lsm_refine(I1, I2, p1, start, Eigen::Matrix2d::Identity(), masked);
      ASSERT_TRUE(r.ok()) << px << " " << py << ": " << to_string(r.status) << " corr " << r.corr << " inliers " << r.corr_inliers;
      EXPECT_LT((r.p2 - truth).norm(), 0.05) << px << " " << py;
      EXPECT_GT(r.corr_inliers, r.corr + 0.02);
      EXPECT_LT(r.inlier_share, 0.97);  // the shadows' pixels are out
      EXPECT_GT(r.inlier_share, 0.7);   // and not much else
      const LsmResult q = lsm_refine(I1, I2, p1, start, Eigen::Matrix2d::Identity(), plain);
      EXPECT_EQ(q.status, LsmStatus::LowCorrelation) << "corr " << q.corr;
      EXPECT_NEAR((q.p2 - r.p2).norm(), 0, 1e-9);  // the mask only measured: the same fit
      ++n;
    }
  EXPECT_EQ(n, 9);
}

// The sigma against the error over many windows whose noise level is known: the normal matrix of the
// last L1 iteration (weights taper / |r|) is no covariance and is several times too optimistic; the
// sandwich covariance of the taper-weighted fit comes closer (the rest, a factor of about 3 on these
// windows and on tp-synth's, is taken by PairMatchOptions' calibration, pair_lsm_options).
TEST(Lsm, SandwichSigmaFollowsTheError) {
  Texture tex(31);
  const long S = 200;
  const Eigen::Vector2d c(100, 100), tshift(0.27, 0.18);
  const Raster I1 = render(tex, S, Eigen::Matrix2d::Identity(), c, 300, 3000, 0.0, 1);
  // RMS error per coordinate and RMS sigma over 4 noise draws x 16 windows, noise of standard deviation sd
  auto stats = [&](double sd, bool sandwich) {
    LsmOptions o;
    o.sigma_sandwich = sandwich;
    o.max_sigma = 10;
    o.min_corr = -1;
    double se = 0, ss = 0;
    for (unsigned d = 0; d < 4; ++d) {
      const Raster I2 = render(tex, S, Eigen::Matrix2d::Identity(), c + tshift, 300, 3000, sd, 10 + d);
      for (double px : {40.2, 80.6, 120.3, 160.7})
        for (double py : {40.4, 80.1, 120.7, 160.2}) {
          const Eigen::Vector2d p1(px, py), truth = p1 + tshift;
          const LsmResult r = lsm_refine(I1, I2, p1, truth, Eigen::Matrix2d::Identity(), o);
          if (!r.ok()) continue;
          se += 0.5 * (r.p2 - truth).squaredNorm();
          ss += r.sigma * r.sigma;
        }
    }
    return std::make_pair(std::sqrt(se / 64), std::sqrt(ss / 64));
  };
  for (double sd : {150.0, 600.0}) {
    const auto irls = stats(sd, false), sw = stats(sd, true);
    std::printf("noise %g: rms error %.4f, rms sigma L1 normal matrix %.4f, sandwich %.4f\n", sd, irls.first, irls.second, sw.second);
    EXPECT_GT(irls.first / irls.second, 2.5);                          // the IRLS matrix: far too optimistic
    EXPECT_LT(sw.first / sw.second, 0.75 * irls.first / irls.second);  // the sandwich: closer
    EXPECT_GT(sw.second, irls.second);
  }
}

// A keypoint within a few pixels of an image's edge (LsmOptions::edge_share): the window cut to its
// pixels inside both images still recovers the true position; its sigma says that fewer pixels gave
// it; a window inside both images is refined exactly as without the option; a corner, where less than
// the share remains, is still out of the image.
TEST(Lsm, WindowCutAtTheImageEdge) {
  Texture tex(17);
  const long S = 160;
  const Eigen::Vector2d c(80, 80);
  Eigen::Matrix2d B;
  B << 1.03, 0.04, -0.02, 0.98;
  const Eigen::Vector2d tshift(-6.4, -5.2);  // image 2's content moved: its edges are not image 1's
  const Raster I1 = render(tex, S, Eigen::Matrix2d::Identity(), c, 300, 1000, 3.0, 1);
  const Raster I2 = render(tex, S, B.inverse(), c + tshift, 260, 800, 3.0, 2);
  LsmOptions plain;  // 21 px, taper 3; the fit held within 1.5 px (the cut keeps max_shift + 1 px clear of image 2's edge)
  plain.max_shift = 1.5;
  LsmOptions cut = plain;
  cut.edge_share = 0.4;
  auto truth_of = [&](const Eigen::Vector2d& p1) { return Eigen::Vector2d(c + tshift + B * (p1 - c)); };
  auto start_of = [&](const Eigen::Vector2d& p1) { return Eigen::Vector2d(truth_of(p1) + Eigen::Vector2d(0.4, -0.3)); };
  // 1 to 4 px from image 1's right and bottom edges, and from image 2's left and top edges
  const std::vector<Eigen::Vector2d> edge = {{156.8, 60.4}, {157.6, 120.2}, {155.2, 30.9}, {100.3, 157.2},
                                             {130.4, 158.1}, {11.9, 90.3}, {80.2, 7.9}, {40.5, 7.6}};
  std::vector<double> err, sig_edge;
  for (const Eigen::Vector2d& p1 : edge) {
    const Eigen::Vector2d p2 = truth_of(p1);
    ASSERT_LT(std::min({p1.minCoeff(), S - 1 - p1.maxCoeff(), p2.minCoeff(), S - 1 - p2.maxCoeff()}), 5.0) << p1.transpose();
    ASSERT_GT(std::min({p1.minCoeff(), S - 1 - p1.maxCoeff(), p2.minCoeff(), S - 1 - p2.maxCoeff()}), 0.5) << p1.transpose();
    EXPECT_EQ(lsm_refine(I1, I2, p1, start_of(p1), Eigen::Matrix2d::Identity(), plain).status, LsmStatus::OutOfImage);
    const LsmResult r = lsm_refine(I1, I2, p1, start_of(p1), Eigen::Matrix2d::Identity(), cut);
    ASSERT_TRUE(r.ok()) << p1.transpose() << ": " << to_string(r.status);
    err.push_back((r.p2 - truth_of(p1)).norm());
    sig_edge.push_back(r.sigma);
  }
  std::vector<double> sig_inside;
  for (double px : {40.3, 80.6, 120.2})
    for (double py : {40.7, 80.2, 120.5}) {
      const Eigen::Vector2d p1(px, py);
      const LsmResult a = lsm_refine(I1, I2, p1, start_of(p1), Eigen::Matrix2d::Identity(), plain);
      const LsmResult b = lsm_refine(I1, I2, p1, start_of(p1), Eigen::Matrix2d::Identity(), cut);
      ASSERT_TRUE(a.ok());
      EXPECT_EQ(a.p2, b.p2);
      EXPECT_EQ(a.sigma, b.sigma);
      EXPECT_EQ(a.corr, b.corr);
      sig_inside.push_back(a.sigma);
    }
  std::sort(err.begin(), err.end());
  EXPECT_LT(err[err.size() / 2], 0.03);
  EXPECT_LT(err.back(), 0.08);
  std::sort(sig_edge.begin(), sig_edge.end());
  std::sort(sig_inside.begin(), sig_inside.end());
  std::printf("window cut at the edge: error median %.4f max %.4f px; median sigma %.4f, inside %.4f px\n", err[err.size() / 2], err.back(),
              sig_edge[sig_edge.size() / 2], sig_inside[sig_inside.size() / 2]);
  EXPECT_GT(sig_edge[sig_edge.size() / 2], 1.2 * sig_inside[sig_inside.size() / 2]);
  // a corner keeps about a quarter of the taper's weight: below the share
  const Eigen::Vector2d corner(158.6, 158.7);
  EXPECT_EQ(lsm_refine(I1, I2, corner, start_of(corner), Eigen::Matrix2d::Identity(), cut).status, LsmStatus::OutOfImage);
}
