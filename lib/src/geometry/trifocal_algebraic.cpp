#include "tpkit/geometry/trifocal_algebraic.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <cmath>

#include "tpkit/geometry/camera_recovery.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/geometry/trifocal_affine_dlt.hpp"

namespace tpkit {

namespace {

// E (16 x 14): the affine tensor entries from the free camera entries, given unit epipoles.
Eigen::Matrix<double, 16, 14> epipole_matrix(const Eigen::Vector3d& e2, const Eigen::Vector3d& e3) {
  // parameter index of a_i[j] and b_i[k]: a1[0..1] 0-1, a2[0..1] 2-3, a3[0..2] 4-6, b1 7-8, b2 9-10, b3 11-13
  auto ai = [](int i, int j) { return i < 2 ? 2 * i + j : 4 + j; };
  auto bi = [](int i, int k) { return i < 2 ? 7 + 2 * i + k : 11 + k; };
  Eigen::Matrix<double, 16, 14> E = Eigen::Matrix<double, 16, 14>::Zero();
  const auto& idx = affine_nonzero_indices();
  for (int c = 0; c < 16; ++c) {
    const int i = idx[c] / 9, j = (idx[c] / 3) % 3, k = idx[c] % 3;
    // T_i(j,k) = a_i[j] e''[k] - e'[j] b_i[k]; a_i[2], b_i[2] exist only for i = 2 (affine cameras)
    if (i == 2 || j < 2) E(c, ai(i, j)) += e3(k);
    if (i == 2 || k < 2) E(c, bi(i, k)) -= e2(j);
  }
  return E;
}

struct AlgebraicSolution {
  Vector16d t;
  double cost;
};

AlgebraicSolution solve_given_epipoles(const Matrix16d& N, double th2, double th3) {
  const Eigen::Vector3d e2(std::cos(th2), std::sin(th2), 0), e3(std::cos(th3), std::sin(th3), 0);
  const Eigen::Matrix<double, 16, 14> E = epipole_matrix(e2, e3);
  Eigen::JacobiSVD<Eigen::Matrix<double, 16, 14>> svd(E, Eigen::ComputeFullU);
  int r = 0;
  while (r < 14 && svd.singularValues()(r) > 1e-10 * svd.singularValues()(0)) ++r;
  const Eigen::MatrixXd Up = svd.matrixU().leftCols(r);
  const Eigen::MatrixXd G = Up.transpose() * N * Up;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(G);
  AlgebraicSolution s;
  s.t = Up * es.eigenvectors().col(0);
  s.cost = std::max(0.0, es.eigenvalues()(0));
  return s;
}

// Residual R t(th', th'') with R^T R = N, so that the squared norm is the algebraic error t^T N t.
struct EpipoleCost {
  EpipoleCost(const Matrix16d& N, const Eigen::Matrix<double, 16, 16>& R, const Vector16d& ref)
      : N_(N), R_(R), ref_(ref) {}
  bool operator()(const double* th, double* res) const {
    AlgebraicSolution s = solve_given_epipoles(N_, th[0], th[1]);
    if (s.t.dot(ref_) < 0) s.t = -s.t;  // continuous sign for the numerical derivative
    Eigen::Map<Vector16d> out(res);
    out = R_ * s.t;
    return s.t.allFinite();
  }
  const Matrix16d& N_;
  const Eigen::Matrix<double, 16, 16>& R_;
  const Vector16d& ref_;
};

}  // namespace

TrifocalTensor trifocal_algebraic(const Eigen::MatrixXd& xy) {
  if (xy.rows() < kAffineMinTracks) throw InputError("algebraic needs at least 4 tracks");
  const auto H = isotropic_normalization(xy, false);
  const Eigen::MatrixXd xn = apply_normalization(xy, H);
  const Matrix16d N = affine_incidence_normal_matrix(xn);
  const Vector16d t0 = smallest_eigenvector(N);
  const TrifocalTensor T0 = affine_tensor_from_vector(t0);
  const TrifocalEpipoles e = trifocal_epipoles(T0);
  double th[2] = {std::atan2(e.e2(1), e.e2(0)), std::atan2(e.e3(1), e.e3(0))};
  // R with R^T R = N from the eigen decomposition (N may be singular for exact data)
  Eigen::SelfAdjointEigenSolver<Matrix16d> es(N);
  const Eigen::Matrix<double, 16, 16> R =
      es.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * es.eigenvectors().transpose();
  ceres::Problem problem;
  problem.AddResidualBlock(
      new ceres::NumericDiffCostFunction<EpipoleCost, ceres::CENTRAL, 16, 2>(new EpipoleCost(N, R, t0)), nullptr, th);
  ceres::Solver::Options opt;
  opt.linear_solver_type = ceres::DENSE_QR;
  opt.max_num_iterations = 50;
  opt.function_tolerance = 1e-15;
  opt.gradient_tolerance = 1e-20;
  opt.parameter_tolerance = 1e-14;
  opt.num_threads = 1;
  opt.max_num_consecutive_invalid_steps = 20;
  opt.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(opt, &problem, &summary);
  AlgebraicSolution s = solve_given_epipoles(N, th[0], th[1]);
  const TrifocalTensor Tn = affine_tensor_from_vector(s.t);
  return denormalize_affine_trifocal(Tn, H);
}

}  // namespace tpkit
