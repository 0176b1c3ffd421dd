#include "tpkit/geometry/affine_camera.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

namespace tpkit {

Camera affine_camera(const Eigen::Matrix<double, 2, 3>& M, const Eigen::Vector2d& t) {
  Camera P = Camera::Zero();
  P.block<2, 3>(0, 0) = M;
  P.block<2, 1>(0, 3) = t;
  P(2, 3) = 1;
  return P;
}

bool is_affine_camera(const Camera& P, double tol) {
  return std::fabs(P(2, 0)) + std::fabs(P(2, 1)) + std::fabs(P(2, 2)) <= tol * std::fabs(P(2, 3));
}

Eigen::Vector2d project(const Camera& P, const Eigen::Vector3d& X) {
  Eigen::Vector3d x = P * X.homogeneous();
  return x.hnormalized();
}

AffineScene AffineScene::random(const AffineSceneOptions& opt) {
  AffineScene s;
  s.options = opt;
  std::mt19937_64 rng(opt.seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const double G = s.ground_extent;
  // ground patch corners and relief range, to fit each image to [0, size)
  for (int v = 0; v < 3; ++v) {
    // viewing direction: off-nadir angle along track (x) plus a small cross-track component
    double along = (v - 1) * opt.max_view_angle * (0.7 + 0.3 * std::fabs(U(rng)));
    double across = 0.1 * opt.max_view_angle * U(rng);
    Eigen::Matrix3d R = (Eigen::AngleAxisd(0.2 * U(rng), Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(along, Eigen::Vector3d::UnitY()) *
                         Eigen::AngleAxisd(across, Eigen::Vector3d::UnitX()))
                            .toRotationMatrix()
                            .transpose();
    Eigen::Matrix<double, 2, 3> M = R.topRows<2>();
    Eigen::Matrix2d K;
    K << 1.0 + 0.05 * U(rng), 0.03 * U(rng), 0, 1.0 + 0.05 * U(rng);
    M = K * M;
    // scale so the projected patch (with relief) fits the image with a margin
    double zr = opt.relief * G;
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    for (int cx = 0; cx < 2; ++cx)
      for (int cy = 0; cy < 2; ++cy)
        for (int cz = 0; cz < 2; ++cz) {
          Eigen::Vector2d p = M * Eigen::Vector3d(cx * G, cy * G, cz * zr);
          xmin = std::min(xmin, p(0));
          xmax = std::max(xmax, p(0));
          ymin = std::min(ymin, p(1));
          ymax = std::max(ymax, p(1));
        }
    double scale = 0.96 * opt.image_size / std::max(xmax - xmin, ymax - ymin);
    M *= scale;
    Eigen::Vector2d t(0.02 * opt.image_size - scale * xmin, 0.02 * opt.image_size - scale * ymin);
    s.P[v] = affine_camera(M, t);
  }
  return s;
}

Eigen::MatrixXd AffineScene::points(int n, std::uint64_t seed) const {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  // smooth relief: a few random bumps, normalized to [0, relief * G]
  std::mt19937_64 trng(options.seed * 7919 + 17);
  std::uniform_real_distribution<double> V(0.0, 1.0);
  double cx[6], cy[6], w[6], a[6];
  for (int b = 0; b < 6; ++b) {
    cx[b] = V(trng);
    cy[b] = V(trng);
    w[b] = 0.1 + 0.3 * V(trng);
    a[b] = 0.3 + V(trng);
  }
  auto h = [&](double u, double v) {
    double z = 0;
    for (int b = 0; b < 6; ++b) z += a[b] * std::exp(-((u - cx[b]) * (u - cx[b]) + (v - cy[b]) * (v - cy[b])) / (w[b] * w[b]));
    return z;
  };
  double zmax = 0;
  for (int q = 0; q <= 20; ++q)
    for (int r = 0; r <= 20; ++r) zmax = std::max(zmax, h(q / 20.0, r / 20.0));
  Eigen::MatrixXd X(n, 3);
  for (int i = 0; i < n; ++i) {
    double u = U(rng), v = U(rng);
    X(i, 0) = u * ground_extent;
    X(i, 1) = v * ground_extent;
    X(i, 2) = std::min(1.0, h(u, v) / zmax) * options.relief * ground_extent;
  }
  return X;
}

Eigen::MatrixXd AffineScene::project(const Eigen::MatrixXd& X) const {
  Eigen::MatrixXd xy(X.rows(), 6);
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (int v = 0; v < 3; ++v) xy.block<1, 2>(i, 2 * v) = tpkit::project(P[v], X.row(i).transpose()).transpose();
  return xy;
}

TrifocalTensor AffineScene::trifocal() const { return trifocal_from_cameras(P[0], P[1], P[2]); }


AffineScene AffineScene::single_pass(const AffineSceneOptions& opt, double cross, double spread) {
  const AffineSceneOptions& o = opt;
  const std::uint64_t seed = o.seed;
  const double size = o.image_size;
  AffineScene s = AffineScene::random(o);  // points() and the options; the cameras are replaced
  std::mt19937_64 rng(seed * 7 + 5);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const double G = s.ground_extent;
  for (int v = 0; v < 3; ++v) {
    const double along = (v - 1) * o.max_view_angle * (0.7 + 0.3 * std::fabs(U(rng)));
    const double c = cross + spread * U(rng), roll = 0.2 * U(rng);
    const Eigen::Vector3d d = Eigen::Vector3d(std::tan(c), std::tan(along), 1).normalized();
    const Eigen::Vector3d ex = (Eigen::Vector3d::UnitX() - d * d.x()).normalized(), ey = d.cross(ex);
    Eigen::Matrix<double, 2, 3> M;
    M.row(0) = (std::cos(roll) * ex + std::sin(roll) * ey).transpose();
    M.row(1) = (-std::sin(roll) * ex + std::cos(roll) * ey).transpose();
    Eigen::Matrix2d K;
    K << 1.0 + 0.05 * U(rng), 0.03 * U(rng), 0, 1.0 + 0.05 * U(rng);
    M = K * M;
    const double zr = o.relief * G;
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector2d p = M * Eigen::Vector3d((k & 1) * G, ((k >> 1) & 1) * G, ((k >> 2) & 1) * zr);
      xmin = std::min(xmin, p(0));
      xmax = std::max(xmax, p(0));
      ymin = std::min(ymin, p(1));
      ymax = std::max(ymax, p(1));
    }
    const double scale = 0.96 * size / std::max(xmax - xmin, ymax - ymin);
    s.P[v] = affine_camera(scale * M, Eigen::Vector2d(0.02 * size - scale * xmin, 0.02 * size - scale * ymin));
  }
  return s;
}

}  // namespace tpkit
