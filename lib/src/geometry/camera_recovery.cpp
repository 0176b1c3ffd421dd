#include "tpkit/geometry/camera_recovery.hpp"

#include <Eigen/Dense>

#include "tpkit/core/error.hpp"

namespace tpkit {

TrifocalEpipoles trifocal_epipoles(const TrifocalTensor& T) {
  Eigen::Matrix3d Ul, Vr;
  for (int i = 0; i < 3; ++i) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(T[i], Eigen::ComputeFullU | Eigen::ComputeFullV);
    Ul.col(i) = svd.matrixU().col(2);
    Vr.col(i) = svd.matrixV().col(2);
  }
  TrifocalEpipoles e;
  Eigen::JacobiSVD<Eigen::Matrix3d> su(Ul, Eigen::ComputeFullU);
  Eigen::JacobiSVD<Eigen::Matrix3d> sv(Vr, Eigen::ComputeFullU);
  e.e2 = su.matrixU().col(2);
  e.e3 = sv.matrixU().col(2);
  if (!e.e2.allFinite() || !e.e3.allFinite()) throw NumericalError("the epipoles of the trifocal tensor are not finite");
  return e;
}

CameraTriplet cameras_from_trifocal(const TrifocalTensor& T) {
  const TrifocalEpipoles e = trifocal_epipoles(T);
  CameraTriplet P;
  P[0].setZero();
  P[0].block<3, 3>(0, 0).setIdentity();
  const Eigen::Matrix3d E3 = e.e3 * e.e3.transpose() - Eigen::Matrix3d::Identity();
  for (int i = 0; i < 3; ++i) {
    P[1].col(i) = T[i] * e.e3;
    P[2].col(i) = E3 * (T[i].transpose() * e.e2);
  }
  P[1].col(3) = e.e2;
  P[2].col(3) = e.e3;
  for (int v = 1; v < 3; ++v) {
    double n = P[v].row(2).norm();
    if (!(n > 1e-300) || !P[v].allFinite())
      throw NumericalError("camera " + std::to_string(v + 1) + " recovered from the tensor has a zero third row");
    P[v] /= n;
  }
  return P;
}

Eigen::Matrix3d fundamental21_from_trifocal(const TrifocalTensor& T) {
  const TrifocalEpipoles e = trifocal_epipoles(T);
  Eigen::Matrix3d M;
  for (int i = 0; i < 3; ++i) M.col(i) = T[i] * e.e3;
  return skew(e.e2) * M;
}

Eigen::Vector4d camera_centre(const Camera& P) {
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  A.topRows<3>() = P;
  Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  return svd.matrixV().col(3);
}

CameraTriplet denormalize_cameras(const CameraTriplet& P, const std::vector<Eigen::Matrix3d>& H) {
  Eigen::Matrix4d G = Eigen::Matrix4d::Identity();
  G.block<3, 3>(0, 0) = H[0];
  CameraTriplet out;
  for (int v = 0; v < 3; ++v) out[v] = H[v].inverse() * P[v] * G;
  return out;
}

}  // namespace tpkit
