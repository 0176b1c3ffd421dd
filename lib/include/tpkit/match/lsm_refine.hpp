// Least-squares matching (LSM) of one correspondence, image 1 -> image 2, on the original radiometry.
//
// The template is the win x win block of image 1's own pixels (not resampled) centred on the pixel
// nearest the keypoint p1 (fixed: p1 stays the keypoint position); the model maps each template
// pixel's offset d = (u, v) from p1 (pixels, fractional, u along x = column) to
//   q(d) = p2 + A d [+ (H0 u^2 + H1 u v + H2 v^2, H3 u^2 + H4 u v + H5 v^2)]   in image 2,
//   and   I1(p1 + d) ~ r0 + r1 * I2(q(d))
// with 6 geometric (p2, A) and 2 radiometric (r0 offset, r1 gain) parameters (+ 6 quadratic terms H),
// solved by Gauss-Newton with bicubic interpolation (Keys, a = -0.5) and its analytic gradient. So p2 is
// the position of p1 itself and A the local map's derivative at p1. Pixels are weighted by the Gaussian
// taper exp(-|d|^2 / (2 taper^2)); with support > 0 (quadratic_support with `quadratic`) only the pixels
// within support x taper of the centre pixel take part in the estimation (the outer ones weigh < 2 %); all
// win x win pixels set the grey-level normalisation and the final correlation. Robust L1 by iteratively reweighted least
// squares (the first two iterations L2), weights taper / max(|r|, eps) (residuals of contrast-normalised
// grey levels); an L1 step along the last one and shorter by rho is stretched by min(2, 1 / (1 - rho))
// (over-relaxation: the same fixed point, reached in fewer iterations). Converged when the IRLS update of
// p2 is below `tolerance` pixels; with L1, not before the first L1 iteration (the third) in the affine
// stage, and not before the fourth iteration in the quadratic stages.
//
// Stages: (0) affine, as above. With `quadratic`: (1) the quadratic model from the affine solution; with
// `adaptive`: (2) the quadratic model again with the taper taper * (c / curvature_ref)^(-1/4) clamped to
// [taper_min, taper_max], c = lsm_curvature(H) of stage 1 (small windows where the map bends, large
// ones where it is smooth). The affine window estimates the window-averaged map, which is biased by
// about taper^2 x (second derivative) on curved (steep) terrain; the quadratic model removes that
// bias at the cost of more noise. A quadratic stage that does not reach `stage_tolerance` within
// `stage_iterations` iterations (or breaks down) falls back to the affine solution. With `epipolar_dir`
// set, the quadratic terms act only along that direction of image 2 (3 parameters, H = e (K0, K1, K2)):
// for affine views the parallax of the terrain moves a point only along the epipolar lines, so this is
// the map's exact second-order form, with 3 fewer unknowns than the general one.
// Precision: the covariance sigma0^2 (J^T W J)^-1 of the final model with sigma0^2 = sum(w r^2) / (n - P),
// J, w and r those of the last iteration (its model within the tolerance of the solution, as is the model
// the correlation is measured at);
// `sigma` = sqrt((var x2 + var y2) / 2) px. It counts image noise only (not model error), and the L1
// weights make it 5-7x too optimistic; with `sigma_sandwich` the covariance is instead the sandwich
// B^-1 M B^-1 of the taper-weighted fit at the solution (B = sum tap J^T J, M = sum tap^2 J^T J, times
// the weighted residual variance), and sigma_scale / sigma_floor calibrate it (match_pair.hpp's
// pair_lsm_options: x 3.5, set on tp-synth truth). sigma_fit keeps the uncalibrated value.
// Residual mask (mask_k > 0): the final correlation is also measured over the window's pixels whose
// residual is within mask_k x 1.4826 x median |residual| (corr_inliers, inlier_share), and the
// acceptance tests that one. With mask_fit_k > 0 the pixels whose residual exceeds mask_fit_k x 1.4826 x
// median |residual| lose their weight in the fit (from the first L1 iteration on).
// Arithmetic: the iterations interpolate image 2 in single precision (4 taps at a time) and build the
// affine normal matrix in single precision, 4 pixels at a time (the covariance inverts it in double);
// positions, residuals and the right-hand side J^T W r (which fixes the solution) are double. Results do
// not depend on threads.
#pragma once
#include <Eigen/Core>
#include <limits>
#include <string>

#include "tpkit/core/image_io.hpp"

namespace tpkit {

struct LsmOptions {
  int window = 21;          // template size in pixels (odd)
  int max_iterations = 40;
  double tolerance = 5e-3;  // pixels, on the update of p2
  // Acceptance of the refined position, by what the fit measures (a rejected refinement is not a lost
  // match: match_keypoints keeps the verified keypoint position, unrefined and marked):
  double max_shift = 2.5;   // pixels: reject when p2 ends farther than this from its initial value
  double max_sigma = 0.15;  // pixels: reject when the position's precision from the normal equations is worse
  double min_corr = 0.5;    // reject when the final normalised cross-correlation (the radiometric fit) is lower
  bool l1 = true;           // robust L1 (IRLS); false: plain least squares
  double eps = 0.02;        // IRLS floor on |r|, in units of the template's grey-level standard deviation
  double taper = 3;         // > 0: Gaussian weight exp(-(u^2+v^2) / (2 taper^2)) on the window (pixels); 0 = flat
  // > 0: only pixels within support x taper of the centre pixel are used (0 = window); quadratic_support
  // for a refinement with the quadratic stages, all of its stages. Under the L1 weights taper / |r| the
  // outer ring counts more than its taper says: the affine model, which takes no curvature, does better
  // without it (synthetic default scene, triplets' views 2+3 median / p90: support 3 0.0671 / 0.1844 px,
  // 2.75 0.0666 / 0.1830, 2.5 0.0651 / 0.1793), and each pixel less is time (253 -> 213 pixels); the
  // quadratic stages, which take the curvature, keep the ring (relief scene p90 0.0475 px at 3, 0.0477-
  // 0.0480 below).
  double support = 2.75;
  double quadratic_support = 3;
  // A window that leaves an image (a match near its edge), > 0: the window is cut to its pixels inside
  // both images (image 2's under the initial model A0, at least max_shift + 1 px inside its edge, so that
  // the fit's moves keep them in) when those hold at least this share of the support's taper weight; the
  // fit, its sigma and the correlation use them alone, and the sigma says what the fewer pixels give.
  // 0: such a window fails as out-of-image. A window inside both images is refined the same either way.
  double edge_share = 0;
  bool quadratic = false;   // second stage with a quadratic geometric model (after the affine converges)
  bool adaptive = true;     // third stage: quadratic with the taper chosen from the second stage's curvature
  // With quadratic: measure how significant the curvature is (LsmResult::curvature_chi2), when the first
  // quadratic stage converges; the refinement itself is unchanged.
  bool measure_curvature = false;
  double curvature_ref = 0.0625;  // adaptive taper = taper * (curvature / curvature_ref)^(-1/4), px^-1
  double taper_min = 2.5, taper_max = 6;  // bounds of the adaptive taper, pixels
  double stage_tolerance = 3e-3;  // pixels, on the update of p2 in the quadratic stages
  int stage_iterations = 30;  // a quadratic stage not converged after this many: keep the affine solution
  // Epipolar direction in image 2 (any length; zero = unknown). When given, the quadratic stages bend the
  // map only along it: q(d) = p2 + A d + e (K0 u^2 + K1 u v + K2 v^2), 3 curvature terms instead of 6.
  Eigen::Vector2d epipolar_dir = Eigen::Vector2d::Zero();
  bool epipolar_curvature = true;  // match_keypoints: pass the verified affine F's epipolar direction
  // The interpolation of image 2 in the x86-64 baseline code even where the CPU has AVX2 (whose code
  // interpolates two pixels at a time, cpu_dispatch.hpp): the same values; for the tests that compare them.
  bool baseline_code = false;
  // Residual mask (images of different dates: shadows that moved, cars, vegetation): the final
  // correlation is also measured over the pixels whose final residual is within mask_k x 1.4826 x the
  // median |residual| of the support (corr_inliers), and a window that keeps less than min_inliers of its
  // pixels is rejected as low-correlation. 0 = off.
  double mask_k = 0;
  double min_inliers = 0.5;
  // The fit's own mask, > 0: from the first L1 iteration on, a pixel whose residual exceeds mask_fit_k x
  // 1.4826 x the median |residual| of the support gets no weight, so the window leaves out what the map
  // cannot follow (a wall's face seen from one side only, a roof edge's occlusion, a changed patch)
  // instead of bending the position to explain it; L1's weights taper / |r| bound one pixel's pull but
  // not a block's. 0 = off (the L1 weights alone). Too tight a threshold takes good texture out: its
  // residuals are the largest where the gradient is (match_pair.hpp's pair_lsm_options: the figures).
  double mask_fit_k = 0;
  // Sigma that predicts the error: sigma = sqrt((sigma_scale x s)^2 + sigma_floor^2), s the normal
  // equations' standard deviation (which counts the residuals as independent, while neighbouring
  // pixels of a sampled, interpolated image are not, and counts no model error). 1 and 0 = s itself.
  double sigma_scale = 1, sigma_floor = 0;
  // The quadratic model's calibration relative to the affine one's: sigma_scale x quadratic_sigma_ratio
  // when the result is the quadratic model's (its sandwich covariance already counts the curvature terms'
  // noise, and it leaves no curvature bias for the scale to cover; pair_lsm_options: 0.6, set on tp-synth's
  // default scene, where at 1 the error / sigma ratio was 0.51-0.66 in the deciles of sigma).
  double quadratic_sigma_ratio = 1;
  // true: s is the sandwich covariance of taper-weighted least squares at the solution (lsm_refine.cpp);
  // false: sigma0^2 (J^T W J)^-1 with the last iteration's L1 weights (about 5x too small on white noise)
  bool sigma_sandwich = false;
};

// Why a refinement was rejected. OffEpipolar is set by match_keypoints (the refined position leaves the
// verified pair model by more than the RANSAC threshold), never by lsm_refine itself.
enum class LsmStatus { Ok, OutOfImage, Invalid, Flat, Diverged, NotConverged, Drifted, LowCorrelation, Imprecise, OffEpipolar };
constexpr int kLsmStatusCount = 10;
const char* to_string(LsmStatus s);

struct LsmResult {
  LsmStatus status = LsmStatus::NotConverged;
  Eigen::Vector2d p2 = Eigen::Vector2d::Zero();  // refined position in image 2, pixels
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  Eigen::Matrix<double, 6, 1> H = Eigen::Matrix<double, 6, 1>::Zero();  // quadratic terms: x (u^2, uv, v^2), y (same)
  double r0 = 0, r1 = 1;  // radiometric offset and gain (normalised grey levels)
  double sigma = 0;       // pixels (calibrated: LsmOptions::sigma_scale, sigma_floor)
  double corr = 0;        // normalised cross-correlation of the template and the resampled window
  int iterations = 0;
  double taper = 0;       // taper of the last stage, pixels
  bool quadratic = false; // the result is the quadratic model's (false: affine, also after a fallback)
  double sigma_fit = 0;   // pixels: the normal equations' standard deviation before calibration
  double corr_inliers = 0;  // correlation over the pixels the residual mask kept (= corr without a mask)
  double inlier_share = 1;  // share of the window's pixels the residual mask kept
  // LsmOptions::measure_curvature: d' (Cq - Ca)^-1 d, d the first quadratic stage's position minus the
  // affine one's, Cq and Ca their sandwich covariances (along the epipolar direction when given): chi-square
  // with 1 (2) degrees of freedom where the map does not curve. NaN when not measured.
  double curvature_chi2 = std::numeric_limits<double>::quiet_NaN();
  bool ok() const { return status == LsmStatus::Ok; }
};

// img1, img2: regions of the two images (Raster::x0/y0 give their place; NaN = invalid pixel).
// p1, p2: positions in full-image pixels; A0: initial local map (e.g. scale ratio x rotation).
LsmResult lsm_refine(const Raster& img1, const Raster& img2, const Eigen::Vector2d& p1, const Eigen::Vector2d& p2,
                     const Eigen::Matrix2d& A0, const LsmOptions& o);

// Curvature of the quadratic terms: sqrt of the sum of squares of the second derivatives of x and y.
double lsm_curvature(const Eigen::Matrix<double, 6, 1>& H);

// Bicubic (Keys a = -0.5) value and gradient at (x, y) in full-image pixels; false outside the
// region's interpolation support or when a NaN is involved.
bool bicubic(const Raster& r, double x, double y, double& value, double* gx = nullptr, double* gy = nullptr);

}  // namespace tpkit
