#include "tpkit/geometry/trifocal_transfer.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "tpkit/geometry/camera_recovery.hpp"
#include "tpkit/core/error.hpp"

namespace tpkit {

Eigen::MatrixXd transfer_point_line_point(const TrifocalTensor& T, const Eigen::MatrixXd& pairs) {
  if (pairs.cols() != 4) throw InputError("point transfer needs pairs x1 y1 x2 y2");
  const Eigen::Index n = pairs.rows();
  Eigen::MatrixXd out(n, 2);
  if (n == 0) return out;
  for (Eigen::Index r = 0; r < n; ++r)
    if (!pairs.row(r).allFinite()) throw InputError("pair record " + std::to_string(r + 1) + " is not finite");
  // conditioning: shift each view to the centroid, one common scale; view 3 uses view 2's frame
  double cx1 = pairs.col(0).mean(), cy1 = pairs.col(1).mean(), cx2 = pairs.col(2).mean(), cy2 = pairs.col(3).mean();
  double spread = 0;
  for (Eigen::Index r = 0; r < n; ++r)
    spread += std::hypot(pairs(r, 0) - cx1, pairs(r, 1) - cy1) + std::hypot(pairs(r, 2) - cx2, pairs(r, 3) - cy2);
  spread /= 2.0 * n;
  double s = spread > 0 ? std::sqrt(2.0) / spread : 1.0 / std::max(1.0, std::fabs(cx1) + std::fabs(cy1));
  auto sim = [&](double cx, double cy) {
    Eigen::Matrix3d H;
    H << s, 0, -s * cx, 0, s, -s * cy, 0, 0, 1;
    return H;
  };
  const Eigen::Matrix3d H1 = sim(cx1, cy1), H2 = sim(cx2, cy2), H3 = sim(cx2, cy2);
  const TrifocalTensor Tn = unit_trifocal(transform_trifocal(T, H1, H2, H3));
  const Eigen::Matrix3d F = fundamental21_from_trifocal(Tn);
  const Eigen::Matrix3d H3i = H3.inverse();
  for (Eigen::Index r = 0; r < n; ++r) {
    Eigen::Vector3d x = H1 * Eigen::Vector3d(pairs(r, 0), pairs(r, 1), 1.0);
    Eigen::Vector3d xp = H2 * Eigen::Vector3d(pairs(r, 2), pairs(r, 3), 1.0);
    // Sampson correction of (x, x') onto x'^T F x = 0
    const double eps = xp.dot(F * x);
    const Eigen::Vector3d Fx = F * x, Ftxp = F.transpose() * xp;
    const double den = Fx(0) * Fx(0) + Fx(1) * Fx(1) + Ftxp(0) * Ftxp(0) + Ftxp(1) * Ftxp(1);
    if (den > 0) {
      const double l = eps / den;
      x(0) -= l * Ftxp(0);
      x(1) -= l * Ftxp(1);
      xp(0) -= l * Fx(0);
      xp(1) -= l * Fx(1);
    }
    const Eigen::Vector3d le = F * x;  // epipolar line of x in view 2
    if (!(std::hypot(le(0), le(1)) > 0))
      throw NumericalError("pair record " + std::to_string(r + 1) + ": no epipolar line (point at the epipole)");
    const Eigen::Vector3d lp(le(1), -le(0), -le(1) * xp(0) + le(0) * xp(1));
    Eigen::Vector3d x3 = Eigen::Vector3d::Zero();
    for (int i = 0; i < 3; ++i) x3 += x(i) * (Tn[i].transpose() * lp);
    x3 = H3i * x3;
    if (!(std::fabs(x3(2)) > 1e-14 * x3.norm()) || !x3.allFinite())
      throw NumericalError("pair record " + std::to_string(r + 1) + " transfers to a point at infinity of view 3");
    out(r, 0) = x3(0) / x3(2);
    out(r, 1) = x3(1) / x3(2);
  }
  return out;
}

}  // namespace tpkit
