#include "tpkit/geometry/trifocal_ml.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "tpkit/geometry/affine_camera.hpp"
#include "tpkit/core/error.hpp"

namespace tpkit {

AffineTrifocalFit trifocal_ml(const Eigen::MatrixXd& xy) {
  if (xy.rows() < kMlMinTracks) throw InputError("ml needs at least 4 tracks");
  const auto H = isotropic_normalization(xy, true);
  const Eigen::MatrixXd xn = apply_normalization(xy, H);  // centred, one scale
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  C.selfadjointView<Eigen::Lower>().rankUpdate(xn.transpose());
  C = C.selfadjointView<Eigen::Lower>();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(C);
  if (es.info() != Eigen::Success) throw NumericalError("ml: eigen decomposition failed");
  AffineTrifocalFit fit;
  for (int q = 0; q < 6; ++q) fit.singular_values(q) = std::sqrt(std::max(0.0, es.eigenvalues()(5 - q)));
  if (!(fit.singular_values(2) > 1e-9 * fit.singular_values(0)))
    throw NumericalError("ml: the measurement matrix has rank < 3 (coplanar points)");
  Eigen::Matrix<double, 6, 3> M;
  for (int q = 0; q < 3; ++q) M.col(q) = es.eigenvectors().col(5 - q);
  fit.X = xn * M;  // n x 3
  CameraTriplet Pn;
  for (int v = 0; v < 3; ++v) {
    Pn[v] = affine_camera(M.middleRows<2>(2 * v), Eigen::Vector2d::Zero());
    fit.P[v] = H[v].inverse() * Pn[v];
  }
  const TrifocalTensor Tn = trifocal_from_cameras(Pn[0], Pn[1], Pn[2]);
  TrifocalTensor T = transform_trifocal(Tn, H[0].inverse(), H[1].inverse(), H[2].inverse());
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        if (affine_zero_entry(i, j, k)) T[i](j, k) = 0;
  fit.T = unit_trifocal(T);
  return fit;
}

TrifocalTensor trifocal_ml_tensor(const Eigen::MatrixXd& xy) { return trifocal_ml(xy).T; }

AffineProjector affine_projector(const CameraTriplet& P) {
  Eigen::Matrix<double, 6, 3> M;
  AffineProjector a;
  for (int v = 0; v < 3; ++v) {
    if (!is_affine_camera(P[v], 1e-9)) throw NumericalError("affine_projector: camera is not affine");
    M.middleRows<2>(2 * v) = P[v].block<2, 3>(0, 0) / P[v](2, 3);
    a.t.segment<2>(2 * v) = P[v].block<2, 1>(0, 3) / P[v](2, 3);
  }
  // Q = I - M (M^T M)^-1 M^T via an orthonormal basis of the columns of M
  Eigen::HouseholderQR<Eigen::Matrix<double, 6, 3>> qr(M);
  Eigen::Matrix<double, 6, 3> B = qr.householderQ() * Eigen::Matrix<double, 6, 3>::Identity();
  a.Q = Eigen::Matrix<double, 6, 6>::Identity() - B * B.transpose();
  return a;
}

double AffineProjector::squared_error(const double* x) const {
  Eigen::Matrix<double, 6, 1> d = Eigen::Map<const Eigen::Matrix<double, 6, 1>>(x) - t;
  return (Q * d).squaredNorm();
}

}  // namespace tpkit
