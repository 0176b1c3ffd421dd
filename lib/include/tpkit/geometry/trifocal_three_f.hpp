// The three-fundamental-matrix method of the ISPRS 2000 fragment (Mikhail et al., XIXth congress B3,
// p. 585): the three fundamental matrices estimated linearly, adjusted simultaneously by constrained least
// squares, and the trifocal tensor formed from the adjusted geometry.
//
// Views 1, 2, 3 = x1 y1, x2 y2, x3 y3. F_ij (i < j) with x_i^T F_ij x_j = 0: F12, F13, F23.
//  1. Linear: each F_ij by the normalized 8-point algorithm (>= 8 tracks), 8 independent elements each
//     (24 in all; we fix the scale by ||F_ij|| = 1 rather than by one element = 1).
//  2. Adjustment (Gauss-Helmert with constraints, iterated): per track the three condition equations
//     w = (x1^T F12 x2, x1^T F13 x3, x2^T F23 x3), weighted by (B B^T)^-1 with B = dw/d(pixels), all
//     linearized at the adjusted observations (the least-squares correction of the six coordinates,
//     iterated per track; at the raw observations the fit is biased, issue 15); constraints G1-G3
//     det F_ij = 0; the third compatibility condition e21^T F23 e31 = 0 (H&Z def. 15.6), which the
//     paper's set lacks (without it the three F have 19 degrees of freedom, the tensor 18); the
//     epipolar-plane constraints G4, G5 (eq. 2a/3): the epipolar line of e23 in view 1 (F12 e23) and that
//     of e32 (F13 e32) are the same line, the trace of the trifocal plane; G6-G9 (eq. 4): F23 e32 = 0 and
//     F23^T e23 = 0, which define the four added parameters, the epipoles e23 (camera 3 in view 2) and
//     e32 (camera 2 in view 3). Unreadable in the fragment, our choices: the epipoles are unit vectors
//     e = (cos p cos t, cos p sin t, sin p) with (t, p) the two added parameters each, not (x, y, 1),
//     because satellite (affine) epipoles lie at infinity; the two equations kept from each 3-vector
//     equation are its components on an orthonormal basis of the plane it can span (recomputed each
//     iteration), not the first two rows or the ratios to the third, which vanish identically for affine
//     epipoles; and ||F_ij|| = 1 as three more constraints. Steps solve the KKT system of the linearized
//     problem until the relative cost decrease or the step (unit-norm F, angles) is below 1e-10.
//  3. Tensor: P = [I|0], P' = [[e21]_x F21 | e21], P'' = [[e31]_x F31 + e31 v^T | l e31] with (v, l)
//     the least-squares solution of "P''^T F32 P' is antisymmetric" (the adjusted F23 = F32^T), then
//     T = trifocal_from_cameras (H&Z 15.1.2 / 9.5).
// Computed in coordinates shifted to each view's centroid and scaled by one common factor (pixel
// weighting); output on the original pixels, unit norm.
#pragma once
#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

constexpr int kThreeFMinTracks = 8;

struct ThreeFundamental {
  Eigen::Matrix3d F12, F13, F23;  // x_i^T F_ij x_j = 0, on the pixels of the caller's frame
};
// Step 1 alone (normalized 8-point per pair); exposed for tests.
ThreeFundamental three_fundamental_linear(const Eigen::MatrixXd& xy);

// The smallest angle, in degrees (0..90), at which the epipolar lines of two views' points meet in the
// third view, at the views' centroids (c: homogeneous points, one per view, in the F's frame). It is 0
// when the three camera centres are collinear — for affine (satellite) cameras, when the three viewing
// directions lie in one plane, as in a single-pass tri-stereo acquisition — and then the three F
// determine neither the tensor nor a point's transfer (H&Z 15.4); near 0 the transfer error of three-f
// grows as 1/sin of it.
double three_f_epipolar_angle(const Eigen::Matrix3d& F12, const Eigen::Matrix3d& F13, const Eigen::Matrix3d& F23,
                              const Eigen::Vector3d c[3]);
double three_f_epipolar_angle(const ThreeFundamental& f, const Eigen::MatrixXd& xy);

struct ThreeFReport {
  double epipolar_angle_deg = 0;  // three_f_epipolar_angle of the adjusted F
  double min_angle_deg = 0;       // the refusal threshold applied
};
// Refused (NumericalError) when the adjusted F's epipolar angle is below min_angle_deg (0: never).
// Near collinear centres the three F's carry little information on the third camera's position along
// the epipolar lines (the cost of the three epipolar conditions is nearly flat there), yet with the
// adjustment at the adjusted observations and the third compatibility condition three-f's transfer
// error stays within 1.16 to 1.32 times ml's (median by angle bin, n = 100 and 1000, sigma 0.5 px,
// bench_trifocal --coplanar), so it is refused only where the centres are collinear to rounding:
// below kThreeFMinAngleDeg (exact coplanar data gives ~1e-6 deg). Below kThreeFWarnAngleDeg trifocal-fit
// warns: the angle itself is uncertain there (0.5 px noise on coplanar geometry measures 0.003 to 1.6 deg).
constexpr double kThreeFMinAngleDeg = 0.05;
constexpr double kThreeFWarnAngleDeg = 2.0;
TrifocalTensor trifocal_three_f(const Eigen::MatrixXd& xy, double min_angle_deg = kThreeFMinAngleDeg,
                                ThreeFReport* report = nullptr);

}  // namespace tpkit
