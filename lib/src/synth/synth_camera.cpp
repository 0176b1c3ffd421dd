// Cameras of tp-synth (synth_camera.hpp) and the trifocal tensor of three cameras (synth_scene.hpp).
#include "tpkit/synth/synth_camera.hpp"

#include <Eigen/Dense>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>

#include "tpkit/core/error.hpp"
#include "tpkit/synth/synth_scene.hpp"

namespace tpkit {

Eigen::Vector2d SynthCamera::project(const Eigen::Vector3d& X) const {
  const Eigen::Vector3d h = P.leftCols<3>() * X + P.col(3);
  return h.head<2>() / h.z();
}

void SynthCamera::prepare() {
  const Eigen::Matrix3d M = P.leftCols<3>();
  if (affine) {
    // Direction: the null vector of the two first rows, pointing down.
    dir_ = M.row(0).transpose().cross(M.row(1).transpose()).normalized();
    if (dir_.z() > 0) dir_ = -dir_;
    inv_.setIdentity();
    inv_.topLeftCorner<2, 2>() = M.topLeftCorner<2, 2>().inverse();
  } else {
    inv_ = M.inverse();
    centre_ = -inv_ * P.col(3);
  }
}

SynthCamera make_synth_camera(bool affine, double along, double cross, double roll, double altitude, double focal,
                              const Eigen::Vector3d& centre, long size) {
  const Eigen::Vector3d to_sat = Eigen::Vector3d(std::tan(cross), std::tan(along), 1).normalized();
  const Eigen::Vector3d zc = -to_sat;  // optical axis, towards the ground
  Eigen::Vector3d xc = Eigen::Vector3d::UnitX() - zc * zc.x();
  xc.normalize();
  Eigen::Vector3d yc = zc.cross(xc);  // about -Y: rows run south
  const double cr = std::cos(roll), sr = std::sin(roll);
  const Eigen::Vector3d xr = cr * xc + sr * yc, yr = -sr * xc + cr * yc;
  Eigen::Matrix3d R;
  R.row(0) = xr.transpose();
  R.row(1) = yr.transpose();
  R.row(2) = zc.transpose();
  const double range = altitude / to_sat.z();
  const Eigen::Vector3d C = centre + range * to_sat;
  const double c = 0.5 * (size - 1);
  SynthCamera cam;
  cam.affine = affine;
  cam.metres_per_pixel = range / focal;
  if (affine) {
    const double s = 1 / cam.metres_per_pixel;
    cam.P.row(0) << s * xr.transpose(), c - s * xr.dot(centre);
    cam.P.row(1) << s * yr.transpose(), c - s * yr.dot(centre);
    cam.P.row(2) << 0, 0, 0, 1;
  } else {
    Eigen::Matrix3d K;
    K << focal, 0, c, 0, focal, c, 0, 0, 1;
    cam.P.leftCols<3>() = K * R;
    cam.P.col(3) = -K * R * C;
  }
  cam.prepare();
  return cam;
}

std::array<Eigen::Matrix3d, 3> trifocal_from_cameras(const Eigen::Matrix<double, 3, 4>& P1,
                                                     const Eigen::Matrix<double, 3, 4>& P2,
                                                     const Eigen::Matrix<double, 3, 4>& P3) {
  // H = [P1^+ | c] with P1 c = 0, so that P1 H = [I | 0] (P1 has full row rank).
  Eigen::JacobiSVD<Eigen::Matrix4d> svd(Eigen::Matrix4d(
      (Eigen::Matrix4d() << P1, Eigen::RowVector4d::Zero()).finished()), Eigen::ComputeFullV);
  const Eigen::Vector4d c = svd.matrixV().col(3);
  const Eigen::Matrix<double, 4, 3> pinv = Eigen::MatrixXd(P1).completeOrthogonalDecomposition().pseudoInverse();
  Eigen::Matrix4d H;
  H.leftCols<3>() = pinv;
  H.col(3) = c;
  if (!((P1 * H).leftCols<3>() - Eigen::Matrix3d::Identity()).allFinite())
    throw NumericalError("trifocal_from_cameras: camera 1 is degenerate");
  const Eigen::Matrix<double, 3, 4> A = P2 * H, B = P3 * H;
  std::array<Eigen::Matrix3d, 3> T;
  for (int i = 0; i < 3; ++i) T[i] = A.col(i) * B.col(3).transpose() - A.col(3) * B.col(i).transpose();
  return T;
}

}  // namespace tpkit
