#include "tpkit/geometry/trifocal_affine_dlt.hpp"

#include <Eigen/Dense>

#include "tpkit/core/error.hpp"

namespace tpkit {

Matrix16d affine_incidence_normal_matrix(const Eigen::MatrixXd& xn) {
  const auto& idx = affine_nonzero_indices();
  const Eigen::Index n = xn.rows();
  Eigen::Matrix<double, Eigen::Dynamic, 16> A(4 * n, 16);
  for (Eigen::Index r = 0; r < n; ++r) {
    const Eigen::Matrix<double, 4, 27> R =
        trifocal_incidence_rows(track_point(xn, r, 0), track_point(xn, r, 1), track_point(xn, r, 2));
    for (int c = 0; c < 16; ++c) A.block<4, 1>(4 * r, c) = R.col(idx[c]);
  }
  Matrix16d N = Matrix16d::Zero();
  N.selfadjointView<Eigen::Lower>().rankUpdate(A.transpose());
  return N.selfadjointView<Eigen::Lower>();
}

Vector16d smallest_eigenvector(const Matrix16d& N) {
  Eigen::SelfAdjointEigenSolver<Matrix16d> es(N);
  if (es.info() != Eigen::Success) throw NumericalError("affine-dlt: eigen decomposition failed");
  if (es.eigenvalues()(1) <= 1e-13 * es.eigenvalues()(15))
    throw NumericalError("affine-dlt: the linear system has more than one solution (degenerate track configuration)");
  return es.eigenvectors().col(0);
}

TrifocalTensor affine_tensor_from_vector(const Vector16d& t) {
  Vector27 full = Vector27::Zero();
  const auto& idx = affine_nonzero_indices();
  for (int c = 0; c < 16; ++c) full(idx[c]) = t(c);
  return trifocal_from_vector(full);
}

Vector16d affine_vector_from_tensor(const TrifocalTensor& T) {
  const Vector27 full = trifocal_to_vector(T);
  const auto& idx = affine_nonzero_indices();
  Vector16d t;
  for (int c = 0; c < 16; ++c) t(c) = full(idx[c]);
  return t;
}

TrifocalTensor trifocal_affine_dlt(const Eigen::MatrixXd& xy) {
  if (xy.rows() < kAffineMinTracks) throw InputError("affine-dlt needs at least 4 tracks");
  const auto H = isotropic_normalization(xy, false);
  const Eigen::MatrixXd xn = apply_normalization(xy, H);
  const TrifocalTensor Tn = affine_tensor_from_vector(smallest_eigenvector(affine_incidence_normal_matrix(xn)));
  return denormalize_affine_trifocal(Tn, H);
}

}  // namespace tpkit
