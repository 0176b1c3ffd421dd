// The affine fundamental matrix of two affine (parallel projection) views, image 1 -> image 2:
//
//   x2^T F x1 = 0,  F = [0 0 a; 0 0 b; c d e]  <=>  a x2 + b y2 + c x1 + d y1 + e = 0,
//
// pixels x = column, y = row. Normalised so that a^2 + b^2 + c^2 + d^2 = 1; then the residual
// |a x2 + b y2 + c x1 + d y1 + e| is the geometric (= Sampson, exact for this linear form) distance in
// pixels of the correspondence (x1, y1, x2, y2) from the model in R^4 (Hartley & Zisserman §14.2).
// Four correspondences in general position determine it (MINIMUM_SAMPLES = 4).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace tpkit {

struct AffineFundamental {
  Eigen::Vector4d n = Eigen::Vector4d::Zero();  // (a, b, c, d), unit norm
  double e = 0;
  static constexpr int MINIMUM_SAMPLES = 4;
  // Signed geometric distance in pixels (R^4) of a correspondence.
  double residual(double x1, double y1, double x2, double y2) const { return n(0) * x2 + n(1) * y2 + n(2) * x1 + n(3) * y1 + e; }
  // Distance in pixels of (x2, y2) from the epipolar line of (x1, y1) in image 2.
  double epipolar_distance2(double x1, double y1, double x2, double y2) const;
  Eigen::Matrix3d matrix() const;
};

// Least-squares (maximum likelihood under isotropic Gaussian noise on all four coordinates) fit to the
// rows `idx` of xy (n x 4: x1 y1 x2 y2); all rows when idx is empty. Returns false when degenerate.
bool fit_affine_fundamental(const Eigen::MatrixX4d& xy, const std::vector<int>& idx, AffineFundamental& F);

struct AffineFundamentalRansac {
  double threshold = 1.0;     // inlier distance in pixels (geometric, R^4)
  double confidence = 0.9999;
  int max_iterations = 20000;
  uint64_t seed = 1;
};

struct AffineFundamentalResult {
  bool ok = false;
  AffineFundamental F;
  std::vector<char> inlier;   // per row of xy
  int inliers = 0;
  int iterations = 0;
  double rms = 0;             // RMS geometric distance of the inliers, pixels
};

// RANSAC on minimal samples of 4, MSAC score, then a least-squares refit on the inliers repeated until
// the inlier set is stable. Deterministic for a given seed.
AffineFundamentalResult ransac_affine_fundamental(const Eigen::MatrixX4d& xy, const AffineFundamentalRansac& o);

}  // namespace tpkit
