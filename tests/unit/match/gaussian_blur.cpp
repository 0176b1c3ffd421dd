// tpkit's Gaussian blur against OpenCV's (the same kernel and borders: values within rounding), on
// planes wider and narrower than the kernel and its vector blocks; the AVX2 and baseline versions give
// the same values, bit for bit.
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
