// RootSIFT descriptors (root_sift.hpp): the square root of the L1-normalised histogram, quantised as
// COLMAP stores it; distances between them are Hellinger distances of the histograms.
#include "tpkit/match/root_sift.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace tpkit;

namespace {
cv::Mat random_sift_rows(int n, unsigned seed) {
  // SIFT-like rows: sparse gradient histograms of integer values 0..255 (float, as OpenCV returns them)
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> v(0, 255), pick(0, 2);
  cv::Mat m(n, 128, CV_32F);
  for (int r = 0; r < n; ++r)
    for (int k = 0; k < 128; ++k) m.at<float>(r, k) = pick(rng) == 0 ? 0.f : static_cast<float>(v(rng));
  return m;
}
}  // namespace

TEST(RootSift, KnownHistogram) {
  // 16 equal bins: each holds 1/16 of the mass, sqrt 1/4, times 512 = 128; the other bins stay 0
  cv::Mat in = cv::Mat::zeros(1, 128, CV_32F);
  for (int k = 0; k < 16; ++k) in.at<float>(0, 8 * k) = 37.f;
  cv::Mat out = root_sift(in);
  ASSERT_EQ(out.type(), CV_8U);
  for (int k = 0; k < 128; ++k) EXPECT_EQ(out.at<uint8_t>(0, k), k % 8 == 0 ? 128 : 0) << k;
  // one bin holding everything would be 512: saturated at 255
  cv::Mat one = cv::Mat::zeros(1, 128, CV_32F);
  one.at<float>(0, 5) = 200.f;
  EXPECT_EQ(root_sift(one).at<uint8_t>(0, 5), 255);
}

TEST(RootSift, ScaleFreeTypeFreeAndZeroRows) {
  cv::Mat a = random_sift_rows(20, 1);
  cv::Mat a8;
  a.convertTo(a8, CV_8U);
  cv::Mat r = root_sift(a), r8 = root_sift(a8), r2 = root_sift(a * 2);
  EXPECT_EQ(cv::norm(r, r8, cv::NORM_INF), 0);  // CV_8U and CV_32F input alike
  EXPECT_EQ(cv::norm(r, r2, cv::NORM_INF), 0);  // the histogram's scale does not matter
  cv::Mat z = cv::Mat::zeros(2, 128, CV_32F);
  EXPECT_EQ(cv::countNonZero(root_sift(z)), 0);
  EXPECT_EQ(root_sift(cv::Mat(0, 128, CV_32F)).rows, 0);
  EXPECT_THROW(root_sift(cv::Mat::zeros(1, 128, CV_32FC2)), std::invalid_argument);
}

TEST(RootSift, DistancesAreHellingerDistances) {
  // |root(a) - root(b)| / 512 is the Hellinger distance sqrt(sum (sqrt(p) - sqrt(q))^2) of the
  // L1-normalised histograms p, q, up to the quantisation (half a unit a component: < 0.5 sqrt(128) / 512)
  cv::Mat a = random_sift_rows(50, 2), b = random_sift_rows(50, 3);
  cv::Mat ra = root_sift(a), rb = root_sift(b);
  for (int r = 0; r < a.rows; ++r) {
    const double sa = cv::sum(a.row(r))[0], sb = cv::sum(b.row(r))[0];
    double h = 0;
    for (int k = 0; k < 128; ++k) {
      const double d = std::sqrt(a.at<float>(r, k) / sa) - std::sqrt(b.at<float>(r, k) / sb);
      h += d * d;
    }
    const double measured = cv::norm(ra.row(r), rb.row(r), cv::NORM_L2) / 512;
    EXPECT_NEAR(measured, std::sqrt(h), 0.5 * std::sqrt(128.0) / 512) << r;
    EXPECT_NEAR(cv::norm(ra.row(r), cv::NORM_L2) / 512, 1.0, 0.5 * std::sqrt(128.0) / 512);  // unit vectors
  }
}

TEST(RootSift, RowByRowAsWhole) {
  // root_sift_row writes the row root_sift gives, into a caller's buffer
  cv::Mat a = random_sift_rows(5, 4);
  cv::Mat whole = root_sift(a);
  for (int r = 0; r < a.rows; ++r) {
    uint8_t row[128];
    root_sift_row(a, r, row);
    for (int k = 0; k < 128; ++k) EXPECT_EQ(row[k], whole.at<uint8_t>(r, k)) << r << " " << k;
  }
}
