// Sensors of tp-synth's views 2..N (synth_sensor.hpp): the blur is the Gaussian PSF of the sharp rendering,
// independent of the strips, with unblurred noise of the asked sigma added after it; a resolution ratio R
// divides view 2's image scale by R exactly and widens its footprint about R^2 times; a rotation of 90 deg
// turns view 2's pixel coordinates of every truth point exactly (x' = y, y' = size - 1 - x); view 1 is
// untouched by all three; the keys go through scene.params.
#include <gtest/gtest.h>
#include <unistd.h>

#include <opencv2/imgproc.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <vector>

#include "tpkit/core/error.hpp"
#include "tpkit/synth/synth_scene.hpp"
#include "tpkit/synth/synth_sensor.hpp"

using namespace tpkit;

namespace {

SynthParams small(double blur = 0, double ratio = 1, double rotation = 0, double noise = 0) {
  SynthParams p;
  p.seed = 7;
  p.size = 64;
  p.relief = 10;
  p.points = 50;
  p.supersample = 1;
  p.noise = noise;
  p.blur = blur;
  p.resolution_ratio = ratio;
  p.rotation = rotation;
  return p;
}

std::vector<uint16_t> sensor_image(const SynthScene& s, int view, long strip) {
  const long n = s.params().size;
  std::vector<uint16_t> img(static_cast<size_t>(n * n));
  for (long y0 = 0; y0 < n; y0 += strip) s.sensor_rows(view, y0, std::min(strip, n - y0), &img[static_cast<size_t>(y0 * n)]);
  return img;
}

cv::Mat as_mat(std::vector<uint16_t>& img, long n) {
  cv::Mat m;
  cv::Mat(static_cast<int>(n), static_cast<int>(n), CV_16U, img.data()).convertTo(m, CV_64F);
  return m;
}

double polygon_area(const std::array<Eigen::Vector2d, 4>& p) {
  double a = 0;
  for (int i = 0; i < 4; ++i) a += p[i].x() * p[(i + 1) % 4].y() - p[(i + 1) % 4].x() * p[i].y();
  return 0.5 * std::fabs(a);
}

}  // namespace

TEST(SynthSensor, BlurIsTheGaussianOfTheSharpRenderingWhateverTheStrips) {
  const SynthScene blurred(small(1.5)), sharp(small());
  const long n = 64;
  const std::vector<uint16_t> whole = sensor_image(blurred, 1, n);
  EXPECT_EQ(whole, sensor_image(blurred, 1, 5));  // strips of 5 rows: halos of ceil(4.5) = 5 rows each
  EXPECT_EQ(whole, sensor_image(blurred, 1, 1));
  std::vector<uint16_t> s = sensor_image(sharp, 1, n), b = whole;
  cv::Mat expect;
  cv::GaussianBlur(as_mat(s, n), expect, cv::Size(11, 11), 1.5, 1.5, cv::BORDER_REPLICATE);
  cv::Mat diff = cv::abs(as_mat(b, n) - expect);
  double worst = 0;
  cv::minMaxLoc(diff, nullptr, &worst);
  EXPECT_LE(worst, 0.5 + 1e-9);  // rounding only
  // The blur removes detail: the mean squared difference of neighbouring pixels drops well below the sharp one's.
  auto roughness = [&](cv::Mat m) { return cv::mean((m.colRange(1, n) - m.colRange(0, n - 1)).mul(m.colRange(1, n) - m.colRange(0, n - 1)))[0]; };
  EXPECT_LT(roughness(as_mat(b, n)), 0.5 * roughness(as_mat(s, n)));
  // View 1 is not blurred.
  EXPECT_EQ(sensor_image(blurred, 0, n), sensor_image(sharp, 0, n));
}

TEST(SynthSensor, NoiseIsAddedAfterTheBlur) {
  const SynthScene clean(small(2.0)), noisy(small(2.0, 1, 0, 3.0));
  const long n = 64;
  std::vector<uint16_t> c = sensor_image(clean, 1, 16), v = sensor_image(noisy, 1, 16);
  cv::Mat d = as_mat(v, n) - as_mat(c, n);
  cv::Scalar mean, sd;
  cv::meanStdDev(d, mean, sd);
  EXPECT_NEAR(mean[0], 0, 0.15);
  EXPECT_NEAR(sd[0], std::sqrt(9 + 1.0 / 12), 0.15);  // sigma 3, not the ~0.3 a blur of sigma 2 would leave
  // white: neighbours uncorrelated
  const double corr = cv::mean(d.colRange(1, n).mul(d.colRange(0, n - 1)))[0] / (sd[0] * sd[0]);
  EXPECT_LT(std::fabs(corr), 0.08);
}

TEST(SynthSensor, ResolutionRatioScalesTheImageOfViewsTwoToN) {
  for (double R : {2.0, 3.0}) {
    const SynthScene base(small()), coarse(small(0, R));
    // affine cameras: x = A X + t; views 2..N's A is base's / R, view 1's unchanged
    EXPECT_TRUE(coarse.camera(0).leftCols<3>().isApprox(base.camera(0).leftCols<3>(), 1e-12));
    for (int v = 1; v < 3; ++v) {
      EXPECT_TRUE((R * coarse.camera(v).leftCols<3>()).isApprox(base.camera(v).leftCols<3>(), 1e-12)) << "view " << v + 1;
      const double a = polygon_area(coarse.footprint(v)) / polygon_area(base.footprint(v));
      EXPECT_NEAR(a, R * R, 1e-6 * R * R) << "view " << v + 1;
    }
    // the truth is the cameras' projection
    const SynthTruth t = synth_truth_points(coarse, 50);
    for (Eigen::Index i = 0; i < t.xy.rows(); ++i)
      for (int v = 0; v < 3; ++v)
        EXPECT_LT((t.xy.block<1, 2>(i, 2 * v).transpose() - coarse.project(v, t.ground.row(i).transpose())).norm(), 1e-9);
  }
}

TEST(SynthSensor, RotationOfNinetyDegreesTurnsViewTwosPixels) {
  const SynthScene base(small()), turned(small(0, 1, 90));
  ASSERT_NEAR(turned.scene_size(), base.scene_size(), 1e-9 * base.scene_size());  // a square turned by 90 still fits
  const SynthTruth t = synth_truth_points(base, 50);
  const double last = 63;
  for (Eigen::Index i = 0; i < t.xy.rows(); ++i) {
    const Eigen::Vector3d X = t.ground.row(i).transpose();
    for (int v = 1; v < 3; ++v) {
      const Eigen::Vector2d a = base.project(v, X), b = turned.project(v, X);
      EXPECT_NEAR(b.x(), a.y(), 1e-6);
      EXPECT_NEAR(b.y(), last - a.x(), 1e-6);
    }
    EXPECT_LT((turned.project(0, X) - base.project(0, X)).norm(), 1e-9);
  }
  // and for any angle the roll of views 2..N grows by it, view 1's not
  const SynthScene thirty(small(0, 1, 30));
  EXPECT_NEAR(thirty.view_angles(1).z() - base.view_angles(1).z(), 30, 1e-9);
  EXPECT_NEAR(thirty.view_angles(0).z(), base.view_angles(0).z(), 1e-12);
}

TEST(SynthSensor, ParamsRoundTripAndRanges) {
  const std::string dir = std::filesystem::temp_directory_path().string() + "/synth_sensor_test_" + std::to_string(getpid());
  std::filesystem::create_directories(dir);
  SynthParams p = small(1.25, 2.5, -30);
  save_params(dir + "/scene.params", p);
  const SynthParams q = load_params(dir + "/scene.params");
  EXPECT_EQ(q.blur, 1.25);
  EXPECT_EQ(q.resolution_ratio, 2.5);
  EXPECT_EQ(q.rotation, -30);
  std::filesystem::remove_all(dir);
  EXPECT_TRUE(synth_has_sensor(p));
  EXPECT_FALSE(synth_has_sensor(small()));
  for (const auto& bad : {small(-1), small(5.5), small(NAN), small(0, 0.5), small(0, 4.5), small(0, 1, 181), small(0, 1, NAN)})
    EXPECT_THROW(check_params(bad), UsageError);
}
