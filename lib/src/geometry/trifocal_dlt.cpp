#include "tpkit/trifocal_dlt.hpp"

#include <Eigen/Dense>

#include "tpkit/error.hpp"

namespace tpkit {

TrifocalTensor trifocal_dlt(const Eigen::MatrixXd& xy) {
  if (xy.rows() < kDltMinTracks) throw InputError("dlt needs at least 7 tracks");
  const auto H = isotropic_normalization(xy, false);
  const Eigen::MatrixXd xn = apply_normalization(xy, H);
  const Eigen::Index n = xn.rows();
  Eigen::Matrix<double, Eigen::Dynamic, 27> A(4 * n, 27);
  for (Eigen::Index r = 0; r < n; ++r)
    A.middleRows<4>(4 * r) = trifocal_incidence_rows(track_point(xn, r, 0), track_point(xn, r, 1), track_point(xn, r, 2));
  Eigen::Matrix<double, 27, 27> N = Eigen::Matrix<double, 27, 27>::Zero();
  N.selfadjointView<Eigen::Lower>().rankUpdate(A.transpose());
  N = N.selfadjointView<Eigen::Lower>();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 27, 27>> es(N);
  if (es.info() != Eigen::Success) throw NumericalError("dlt: eigen decomposition failed");
  const Vector27 t = es.eigenvectors().col(0);
  if (es.eigenvalues()(1) <= 1e-13 * es.eigenvalues()(26))
    throw NumericalError("dlt: the linear system has more than one solution (degenerate track configuration)");
  const TrifocalTensor Tn = trifocal_from_vector(t);
  return unit_trifocal(transform_trifocal(Tn, H[0].inverse(), H[1].inverse(), H[2].inverse()));
}

}  // namespace tpkit
