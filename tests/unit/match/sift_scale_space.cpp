// tpkit's scale space against the truth and against OpenCV's SIFT, the method it implements: a Gaussian
// blob is found at its centre with its scale; on a textured image nearly every keypoint has an OpenCV
// twin (the same extremum 0.25 px away by OpenCV's upsampling convention, the same size and angle) and a
// close descriptor; a rotated image gives rotated keypoints whose descriptors match; the mask is honoured.
#include "tpkit/match/sift_scale_space.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

using namespace tpkit;

namespace {
// Elongated blobs of several sizes and directions at random sub-pixel places on a mid-grey background,
// 8-bit: a texture whose neighbourhoods differ.
cv::Mat textured(int w, int h, unsigned seed) {
  cv::Mat f(h, w, CV_32F, cv::Scalar(128));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0, w), uy(0, h), us(1.2, 6), ue(1, 2.5), ut(0, CV_PI), ua(-90, 90);
  for (int b = 0; b < w * h / 300; ++b) {
    const double x0 = ux(rng), y0 = uy(rng), s = us(rng), e = ue(rng), t = ut(rng), a = ua(rng);
    const double c = std::cos(t), sn = std::sin(t);
    const int r = static_cast<int>(std::ceil(4 * s * e));
    for (int y = std::max(0, static_cast<int>(y0) - r); y < std::min(h, static_cast<int>(y0) + r + 1); ++y)
      for (int x = std::max(0, static_cast<int>(x0) - r); x < std::min(w, static_cast<int>(x0) + r + 1); ++x) {
        const double p = (x - x0) * c + (y - y0) * sn, q = -(x - x0) * sn + (y - y0) * c;
        f.at<float>(y, x) += static_cast<float>(a * std::exp(-(p * p / (e * e) + q * q) / (2 * s * s)));
      }
  }
  cv::Mat u8;
  f.convertTo(u8, CV_8U);
  return u8;
}

// One bright round Gaussian blob of sigma s centred at (x0, y0) on a dark n x n background, 8-bit.
cv::Mat gaussian_blob(int n, double x0, double y0, double s) {
  cv::Mat f(n, n, CV_32F);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      f.at<float>(y, x) = static_cast<float>(40 + 180 * std::exp(-((x - x0) * (x - x0) + (y - y0) * (y - y0)) / (2 * s * s)));
  cv::Mat u8;
  f.convertTo(u8, CV_8U);
  return u8;
}

ScaleSpaceOptions tpkit_defaults() {
  ScaleSpaceOptions o;
  o.contrast = 0.02;
  o.edge = 14;
  return o;
}
}  // namespace

TEST(SiftScaleSpace, GaussianBlobFoundAtItsCentreWithItsScale) {
  // one bright Gaussian blob of sigma s at a sub-pixel place: the DoG extremum of scale s lies at its
  // centre; OpenCV's convention would put it 0.25 px right of and below it
  const double x0 = 40.3, y0 = 37.7, s = 3.0;
  const cv::Mat u8 = gaussian_blob(80, x0, y0, s);
  std::vector<cv::KeyPoint> kp;
  cv::Mat desc;
  detect_sift_scale_space(u8, cv::Mat(), tpkit_defaults(), kp, desc);
  ASSERT_FALSE(kp.empty());
  ASSERT_EQ(desc.rows, static_cast<int>(kp.size()));
  const cv::KeyPoint& k = *std::max_element(kp.begin(), kp.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response < b.response; });
  EXPECT_NEAR(k.pt.x, x0, 0.05);
  EXPECT_NEAR(k.pt.y, y0, 0.05);
  // size = 2 x the scale; the difference of Gaussians of a blob of sigma s peaks at a scale near s
  // (0.88 s here, as OpenCV's)
  EXPECT_GT(k.size / 2, 0.8 * s);
  EXPECT_LT(k.size / 2, 1.2 * s);
}

TEST(SiftScaleSpace, AgreesWithOpenCvSift) {
  const cv::Mat img = textured(384, 320, 7);
  std::vector<cv::KeyPoint> kp, ref;
  cv::Mat desc, rdesc;
  const ScaleSpaceOptions o = tpkit_defaults();
  detect_sift_scale_space(img, cv::Mat(), o, kp, desc);
  cv::SIFT::create(0, o.octave_layers, o.contrast, o.edge, o.sigma)->detectAndCompute(img, cv::Mat(), ref, rdesc);
  ASSERT_GT(kp.size(), 300u);
  EXPECT_NEAR(static_cast<double>(kp.size()), static_cast<double>(ref.size()), 0.02 * static_cast<double>(ref.size()));
  int twins = 0;
  double dist = 0, norm = 0;
  for (size_t i = 0; i < kp.size(); ++i) {
    int best = -1;
    double bd = 1e9;
    for (size_t j = 0; j < ref.size(); ++j) {
      const double dx = ref[j].pt.x - 0.25 - kp[i].pt.x, dy = ref[j].pt.y - 0.25 - kp[i].pt.y;
      double da = std::abs(ref[j].angle - kp[i].angle);
      da = std::min(da, 360 - da);
      if (da > 1 || std::abs(ref[j].size / kp[i].size - 1) > 0.01) continue;
      if (dx * dx + dy * dy < bd) bd = dx * dx + dy * dy, best = static_cast<int>(j);
    }
    if (best < 0 || bd > 0.02 * 0.02) continue;
    ++twins;
    dist += cv::norm(desc.row(static_cast<int>(i)), rdesc.row(best), cv::NORM_L2);
    norm += cv::norm(rdesc.row(best), cv::NORM_L2);
  }
  EXPECT_GT(twins, static_cast<int>(0.97 * static_cast<double>(kp.size())));
  // descriptors differ only by the sub-pixel centring of the window and float rounding
  EXPECT_LT(dist / norm, 0.10);
}

TEST(SiftScaleSpace, RotatedImageGivesRotatedKeypointsAndMatchingDescriptors) {
  const cv::Mat img = textured(300, 300, 11);
  cv::Mat rot;
  cv::rotate(img, rot, cv::ROTATE_90_CLOCKWISE);  // (x, y) -> (H - 1 - y, x)
  std::vector<cv::KeyPoint> a, b;
  cv::Mat da, db;
  detect_sift_scale_space(img, cv::Mat(), tpkit_defaults(), a, da);
  detect_sift_scale_space(rot, cv::Mat(), tpkit_defaults(), b, db);
  int matched = 0, correct = 0;
  cv::BFMatcher bf(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  bf.knnMatch(da, db, knn, 2);
  for (const auto& m : knn) {
    if (m.size() < 2 || m[0].distance > 0.8 * m[1].distance) continue;
    ++matched;
    const cv::Point2f p = a[m[0].queryIdx].pt, q = b[m[0].trainIdx].pt;
    if (std::hypot(q.x - (299 - p.y), q.y - p.x) < 0.3) ++correct;
  }
  EXPECT_GT(matched, static_cast<int>(0.5 * static_cast<double>(a.size())));
  EXPECT_GT(correct, static_cast<int>(0.93 * matched));  // 97% here; the rest are look-alike blobs
}

TEST(SiftScaleSpace, MaskAndBadInput) {
  const cv::Mat img = textured(200, 160, 3);
  cv::Mat mask(img.size(), CV_8U, cv::Scalar(0));
  mask(cv::Rect(0, 0, 100, 160)).setTo(255);
  std::vector<cv::KeyPoint> kp;
  cv::Mat desc;
  detect_sift_scale_space(img, mask, tpkit_defaults(), kp, desc);
  ASSERT_FALSE(kp.empty());
  for (const auto& k : kp) EXPECT_LT(std::lround(k.pt.x), 100);
  EXPECT_THROW(detect_sift_scale_space(cv::Mat(10, 10, CV_32F), cv::Mat(), tpkit_defaults(), kp, desc), std::invalid_argument);
  EXPECT_THROW(detect_sift_scale_space(img, cv::Mat(5, 5, CV_8U), tpkit_defaults(), kp, desc), std::invalid_argument);
  detect_sift_scale_space(cv::Mat(), cv::Mat(), tpkit_defaults(), kp, desc);
  EXPECT_TRUE(kp.empty());
  EXPECT_EQ(desc.cols, 128);
}

TEST(SiftScaleSpace, LargeSigmaKeepsItsKeypoints) {
  // a first-layer blur of 6 px: orientation windows of radius 34 px and more, all of them kept
  const double x0 = 100.4, y0 = 99.6, s = 10.0;
  const cv::Mat u8 = gaussian_blob(200, x0, y0, s);
  ScaleSpaceOptions o = tpkit_defaults();
  o.sigma = 6;
  std::vector<cv::KeyPoint> kp;
  cv::Mat desc;
  detect_sift_scale_space(u8, cv::Mat(), o, kp, desc);
  ASSERT_FALSE(kp.empty());
  const cv::KeyPoint& k = *std::max_element(kp.begin(), kp.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response < b.response; });
  EXPECT_NEAR(k.pt.x, x0, 0.2);
  EXPECT_NEAR(k.pt.y, y0, 0.2);
}

TEST(SiftScaleSpace, RegionGivesTheWholeImagesKeypointsThere) {
  // a wanted region (a detection tile's core) skips the extrema, orientations and descriptors outside
  // it, and changes nothing inside: the same keypoints, byte for byte, with the same descriptors
  const cv::Mat img = textured(400, 360, 11);
  const ScaleSpaceOptions whole = tpkit_defaults();
  std::vector<cv::KeyPoint> all;
  cv::Mat all_desc;
  detect_sift_scale_space(img, cv::Mat(), whole, all, all_desc);
  for (const ScaleSpaceOptions::Region r : {ScaleSpaceOptions::Region{100.5, 80.5, 300.5, 250.5}, ScaleSpaceOptions::Region{-0.5, 37.25, 171, 359.5}}) {
    ScaleSpaceOptions o = whole;
    o.region = r;
    std::vector<cv::KeyPoint> kp;
    cv::Mat desc;
    detect_sift_scale_space(img, cv::Mat(), o, kp, desc);
    std::vector<int> inside;
    for (int i = 0; i < static_cast<int>(all.size()); ++i)
      if (r.contains(all[i].pt.x, all[i].pt.y)) inside.push_back(i);
    ASSERT_GT(inside.size(), 100u);
    ASSERT_EQ(kp.size(), inside.size());
    // both lists are in the scale space's order (octave, layer, then row); the region's is a subsequence
    for (size_t j = 0; j < kp.size(); ++j) {
      const cv::KeyPoint& a = all[inside[j]];
      EXPECT_TRUE(a.pt == kp[j].pt && a.size == kp[j].size && a.angle == kp[j].angle && a.response == kp[j].response && a.octave == kp[j].octave) << j;
      EXPECT_EQ(cv::norm(all_desc.row(inside[j]), desc.row(static_cast<int>(j)), cv::NORM_INF), 0) << j;
    }
  }
}
