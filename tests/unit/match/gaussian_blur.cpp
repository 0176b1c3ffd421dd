// tpkit's Gaussian blur against OpenCV's (the same kernel and borders: values within rounding), on
// planes wider and narrower than the kernel and its vector blocks; the AVX2 and baseline versions give
// the same values, bit for bit; a blur over part of the plane gives the whole plane's values there.
#include "tpkit/match/gaussian_blur.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

using namespace tpkit;

TEST(GaussianBlur, AgreesWithOpenCvOnEveryShape) {
  cv::RNG rng(5);
  for (const cv::Size size : {cv::Size(777, 500), cv::Size(64, 40), cv::Size(33, 70), cv::Size(7, 5), cv::Size(1, 9), cv::Size(12, 1)})
    for (const double sigma : {0.8, 1.249, 1.95, 3.1, 6.0}) {
      cv::Mat src(size, CV_32F);
      rng.fill(src, cv::RNG::UNIFORM, 0, 255);
      cv::Mat ref;
      cv::GaussianBlur(src, ref, cv::Size(), sigma, sigma, cv::BORDER_REFLECT_101);
      const cv::Mat got = gaussian_blur(src, sigma);
      ASSERT_EQ(got.size(), src.size());
      ASSERT_EQ(got.type(), CV_32F);
      EXPECT_LT(cv::norm(got, ref, cv::NORM_INF), 2e-4) << size << " sigma " << sigma;
      // the baseline code: the same values
      EXPECT_EQ(cv::norm(got, gaussian_blur(src, sigma, true), cv::NORM_INF), 0) << size << " sigma " << sigma;
    }
}

TEST(GaussianBlur, ConstantStaysAndBadInput) {
  const cv::Mat flat(40, 50, CV_32F, cv::Scalar(100));
  EXPECT_LT(cv::norm(gaussian_blur(flat, 2.0), flat, cv::NORM_INF), 1e-4);
  EXPECT_THROW(gaussian_blur(cv::Mat(10, 10, CV_8U), 1.0), std::invalid_argument);
  EXPECT_THROW(gaussian_blur(flat, 0.0), std::invalid_argument);
  EXPECT_TRUE(gaussian_blur(cv::Mat(0, 0, CV_32F), 1.0).empty());
}

TEST(GaussianBlur, PartOfThePlaneHasTheWholePlanesValues) {
  cv::RNG rng(9);
  cv::Mat src(300, 410, CV_32F);
  rng.fill(src, cv::RNG::UNIFORM, 0, 255);
  for (const double sigma : {1.23, 3.1})
    for (const bool baseline : {false, true}) {
      const cv::Mat whole = gaussian_blur(src, sigma, baseline);
      // inside, at each edge and corner (the borders' reflections), narrower than a vector, past the plane
      for (const cv::Rect roi : {cv::Rect(40, 30, 200, 150), cv::Rect(0, 0, 37, 300), cv::Rect(395, 280, 15, 20), cv::Rect(3, 100, 5, 3),
                                 cv::Rect(200, 250, 300, 100), cv::Rect(1, 1, 408, 298)}) {
        const cv::Mat part = gaussian_blur(src, sigma, roi, baseline);
        ASSERT_EQ(part.size(), src.size());
        const cv::Rect in = roi & cv::Rect(0, 0, src.cols, src.rows);
        EXPECT_EQ(cv::norm(part(in), whole(in), cv::NORM_INF), 0) << roi << " sigma " << sigma << " baseline " << baseline;
      }
    }
  EXPECT_EQ(gaussian_blur_radius(1.23), 5);
  EXPECT_EQ(gaussian_blur_radius(3.1), 13);  // 27 taps
}
