// The trifocal tensor of three views and what every trifocal method shares: conversions, the
// point-point-point incidence equations, coordinate normalization and its exact undoing, input checks.
//
// Conventions (all of tpkit's geometry): views 1, 2, 3 are the columns x1 y1, x2 y2, x3 y3 of a tracks
// file; points are homogeneous pixels x = (x, y, 1) with x = column, y = row, origin at the centre of the
// top-left pixel. T[i](j, k) = T_i^{jk} (Hartley & Zisserman ch. 15, 0-based here): i is the index of the
// view-1 point x, j of the view-2 point x', k of the view-3 point x''. Point-point-point incidence:
//   [x']_x (sum_i x^i T_i) [x'']_x = 0_{3x3}.
// For cameras P = [I|0], P' = [A|a4], P'' = [B|b4]: T_i = a_i b4^T - a4 b_i^T.
// The paper's (Yang, Pan, Huang eq. 11) 1-based numbering t1..t27 is t_{9i+3j+k+1} = T_i(j,k) (0-based
// i, j, k): t1..t9 = T_1 row-major, t10..t18 = T_2, t19..t27 = T_3. Affine cameras give the zero pattern
// t3 t6 t7 t8 t9 t12 t15 t16 t17 t18 t27 (eq. 6), i.e. T_1 and T_2 have zero third row and column and
// T_3(3,3) = 0 (1-based); 16 entries remain.
#pragma once
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace tpkit {

using TrifocalTensor = std::array<Eigen::Matrix3d, 3>;
using Camera = Eigen::Matrix<double, 3, 4>;
using CameraTriplet = std::array<Camera, 3>;
using Vector27 = Eigen::Matrix<double, 27, 1>;

// t[9 i + 3 j + k] = T_i(j, k).
// The cross-product matrix [v]x, with [v]x w = v x w.
Eigen::Matrix3d skew(const Eigen::Vector3d& v);

Vector27 trifocal_to_vector(const TrifocalTensor& T);
TrifocalTensor trifocal_from_vector(const Vector27& t);

// 0-based indices (into the 27-vector) of the 16 entries an affine tensor may have non-zero, ascending.
const std::array<int, 16>& affine_nonzero_indices();
// True if T_i(j, k) must be zero for affine cameras.
bool affine_zero_entry(int i, int j, int k);

// T_i^{jk} = (-1)^i det[P1 without row i; P2 row j; P3 row k] (H&Z eq. 17.12, 0-based i). Any cameras
// (projective or affine); pixel units of whatever frame the cameras map to. Unnormalized scale.
TrifocalTensor trifocal_from_cameras(const Camera& P1, const Camera& P2, const Camera& P3);

// The tensor in new image coordinates x^ = H1 x, x'^ = H2 x', x''^ = H3 x'' (any invertible 3x3):
//   T^_i = H2 (sum_a (H1^-1)(a, i) T_a) H3^T.
// Normalizing then calling this with the inverse transforms undoes the normalization exactly.
TrifocalTensor transform_trifocal(const TrifocalTensor& T, const Eigen::Matrix3d& H1, const Eigen::Matrix3d& H2,
                                  const Eigen::Matrix3d& H3);

// Frobenius norm 1, largest-magnitude entry positive (as the trifocal file stores it).
TrifocalTensor unit_trifocal(const TrifocalTensor& T);
// An affine tensor fitted in normalized coordinates (x_n = H[v] x for view v) back on pixels: the
// exact inverse transform, the affine zero pattern cleared of rounding, Frobenius norm 1. The
// normalizations must be similarities (they keep the zero pattern).
TrifocalTensor denormalize_affine_trifocal(const TrifocalTensor& Tn, const std::vector<Eigen::Matrix3d>& H);

// [x']_x (sum_i x^i T_i) [x'']_x for homogeneous points of views 1, 2, 3 (algebraic residual, 3x3).
Eigen::Matrix3d trifocal_incidence(const TrifocalTensor& T, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                                   const Eigen::Vector3d& x3);

// The four independent incidence equations of one track (rows (p, q) of [x']_x M [x'']_x with p, q in
// {0, 1}, H&Z 16.2): row r dotted with the 27-vector t gives that entry. Points homogeneous (x, y, 1).
Eigen::Matrix<double, 4, 27> trifocal_incidence_rows(const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                                                     const Eigen::Vector3d& x3);

// A similarity x^ = s (x - c) per view (views = xy.cols() / 2), written as 3x3 matrices. With
// `common_scale`, one s for every view (it keeps pixel distances comparable across views, as maximum
// likelihood and equal-weight triangulation need); otherwise each view's mean distance to its centroid
// becomes sqrt(2) (H&Z isotropic normalization). Translation and isotropic scaling are affine, so the
// affine zero pattern of a tensor survives them. Throws NumericalError if a view has no spread.
std::vector<Eigen::Matrix3d> isotropic_normalization(const Eigen::MatrixXd& xy, bool common_scale);

// Applies per-view 3x3 similarities to an n x 2K matrix of pixels.
Eigen::MatrixXd apply_normalization(const Eigen::MatrixXd& xy, const std::vector<Eigen::Matrix3d>& H);

// The checks every trifocal method makes on n x 6 track coordinates (views 1..3, pixels): at least
// `min_points` tracks, all finite, no duplicated track, and not all points of a planar scene (the
// centred 6 x n measurement matrix must have rank 3: flat terrain makes the tensor undetermined).
// `noise_rank_test`: also reject a third singular value at the noise level (sigma3 < 1.3 sigma4, n >= 10);
// off for sets that may hold outliers. Throws InputError / NumericalError with a message naming `method`.
void check_trifocal_input(const Eigen::MatrixXd& xy, int min_points, const std::string& method,
                          bool noise_rank_test = true);

// Homogeneous (x, y, 1) of view v (0..2) of track r.
inline Eigen::Vector3d track_point(const Eigen::MatrixXd& xy, Eigen::Index r, int v) {
  return Eigen::Vector3d(xy(r, 2 * v), xy(r, 2 * v + 1), 1.0);
}

}  // namespace tpkit
