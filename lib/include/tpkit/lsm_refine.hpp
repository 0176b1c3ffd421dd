// Least-squares matching (LSM) of one correspondence, image 1 -> image 2, on the original radiometry.
//
// The template is the win x win block of image 1's own pixels (not resampled) centred on the pixel
// nearest the keypoint p1 (fixed: p1 stays the keypoint position); the model maps each template
// pixel's offset d = (u, v) from p1 (pixels, fractional, u along x = column) to
//   q(d) = p2 + A d        in image 2, and   I1(p1 + d) ~ r0 + r1 * I2(q(d))
// with 6 geometric (p2, A) and 2 radiometric (r0 offset, r1 gain) parameters, solved by Gauss-Newton
// with bicubic interpolation (Keys, a = -0.5) and its analytic gradient. Robust L1 by iteratively
// reweighted least squares, weights 1 / max(|r|, eps) (residuals of contrast-normalised grey levels).
// Converged when the update of p2 is below `tolerance` pixels. Precision: the covariance
// sigma0^2 (J^T W J)^-1 with sigma0^2 = sum(w r^2) / (n - 8); `sigma` = sqrt((var x2 + var y2) / 2) px.
#pragma once
#include <Eigen/Core>
#include <string>

#include "tpkit/image_io.hpp"

namespace tpkit {

struct LsmOptions {
  int window = 21;          // template size in pixels (odd)
  int max_iterations = 40;
  double tolerance = 1e-3;  // pixels, on the update of p2
  double max_shift = 1.5;   // pixels: drop when p2 ends farther than this from its initial value
  double min_corr = 0.8;    // drop when the final normalised cross-correlation is lower
  bool l1 = true;           // robust L1 (IRLS); false: plain least squares
  double eps = 0.02;        // IRLS floor on |r|, in units of the template's grey-level standard deviation
  double taper = 3;         // > 0: Gaussian weight exp(-(u^2+v^2) / (2 taper^2)) on the window (pixels); 0 = flat
};

enum class LsmStatus { Ok, OutOfImage, Invalid, Flat, Diverged, NotConverged, Drifted, LowCorrelation };
const char* to_string(LsmStatus s);

struct LsmResult {
  LsmStatus status = LsmStatus::NotConverged;
  Eigen::Vector2d p2 = Eigen::Vector2d::Zero();  // refined position in image 2, pixels
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  double r0 = 0, r1 = 1;  // radiometric offset and gain (normalised grey levels)
  double sigma = 0;       // pixels
  double corr = 0;        // normalised cross-correlation of the template and the resampled window
  int iterations = 0;
  bool ok() const { return status == LsmStatus::Ok; }
};

// img1, img2: regions of the two images (Raster::x0/y0 give their place; NaN = invalid pixel).
// p1, p2: positions in full-image pixels; A0: initial local map (e.g. scale ratio x rotation).
LsmResult lsm_refine(const Raster& img1, const Raster& img2, const Eigen::Vector2d& p1, const Eigen::Vector2d& p2,
                     const Eigen::Matrix2d& A0, const LsmOptions& o);

// Bicubic (Keys a = -0.5) value and gradient at (x, y) in full-image pixels; false outside the
// region's interpolation support or when a NaN is involved.
bool bicubic(const Raster& r, double x, double y, double& value, double* gx = nullptr, double* gy = nullptr);

}  // namespace tpkit
