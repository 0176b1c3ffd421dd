// The affine linear algorithm (Yang, Pan, Huang §3.3): the incidence equations of trifocal_dlt.hpp
// restricted to the 16 entries that affine cameras leave non-zero (t3 t6 t7 t8 t9 t12 t15 t16 t17 t18
// t27 = 0 in the paper's numbering; see trifocal_tensor.hpp), >= 4 tracks.
//
// Input n x 6 pixels (views 1..3); isotropic per-view normalization (a similarity, hence affine: the zero
// pattern survives it and its undoing). Output on the original pixels, unit norm, zero pattern exact.
#pragma once
#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

constexpr int kAffineMinTracks = 4;
using Matrix16d = Eigen::Matrix<double, 16, 16>;
using Vector16d = Eigen::Matrix<double, 16, 1>;

TrifocalTensor trifocal_affine_dlt(const Eigen::MatrixXd& xy);

// Building blocks on already normalized coordinates (n x 6, any affine frame):
// N = A^T A of the four incidence equations per track over the 16 affine entries (order of
// affine_nonzero_indices()), and the unit 16-vector minimizing t^T N t.
Matrix16d affine_incidence_normal_matrix(const Eigen::MatrixXd& xn);
Vector16d smallest_eigenvector(const Matrix16d& N);
TrifocalTensor affine_tensor_from_vector(const Vector16d& t);
Vector16d affine_vector_from_tensor(const TrifocalTensor& T);

}  // namespace tpkit
