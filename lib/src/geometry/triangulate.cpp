#include "tpkit/geometry/triangulate.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "tpkit/core/error.hpp"

namespace tpkit {

Eigen::Vector4d triangulate_dlt(const CameraTriplet& P, const Eigen::Matrix<double, 1, 6>& pts) {
  Eigen::Matrix<double, 6, 4> D;
  for (int v = 0; v < 3; ++v) {
    D.row(2 * v) = pts(2 * v) * P[v].row(2) - P[v].row(0);
    D.row(2 * v + 1) = pts(2 * v + 1) * P[v].row(2) - P[v].row(1);
  }
  Eigen::JacobiSVD<Eigen::Matrix<double, 6, 4>> svd(D, Eigen::ComputeFullV);
  return svd.matrixV().col(3);
}

Eigen::Matrix<double, 1, 6> reprojection_residual(const CameraTriplet& P, const Eigen::Vector4d& X,
                                                  const Eigen::Matrix<double, 1, 6>& pts) {
  Eigen::Matrix<double, 1, 6> r;
  for (int v = 0; v < 3; ++v) {
    Eigen::Vector3d x = P[v] * X;
    if (!(std::fabs(x(2)) > 1e-300 * x.norm()) || !x.allFinite())
      throw NumericalError("a track triangulates to a point at infinity of view " + std::to_string(v + 1));
    r(2 * v) = x(0) / x(2) - pts(2 * v);
    r(2 * v + 1) = x(1) / x(2) - pts(2 * v + 1);
  }
  if (!r.allFinite()) throw NumericalError("non-finite reprojection residual");
  return r;
}

}  // namespace tpkit
