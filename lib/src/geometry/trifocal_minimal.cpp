#include "tpkit/geometry/trifocal_minimal.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <cmath>

#include "tpkit/geometry/camera_recovery.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/geometry/trifocal_affine_dlt.hpp"

namespace tpkit {

namespace {

Eigen::Vector3d in_plane_unit(const Eigen::Vector3d& e) {
  Eigen::Vector3d d(e(0), e(1), 0);
  double n = d.norm();
  if (!(n > 1e-300)) throw NumericalError("minimal: an epipole is not a direction (cameras are not affine)");
  return d / n;
}

Eigen::Vector3d image_of(const Camera& P, const Eigen::Vector4d& C) { return P * C; }

template <class T>
Eigen::Matrix<T, 3, 3> rot_z(const T& a) {
  using std::cos;
  using std::sin;
  Eigen::Matrix<T, 3, 3> R;
  R << cos(a), -sin(a), T(0), sin(a), cos(a), T(0), T(0), T(0), T(1);
  return R;
}

struct MinimalCost {
  Eigen::Matrix3d U0, V0, W0;
  std::vector<int> pattern;               // 9 m + 3 j + k of the free core entries
  Eigen::Matrix<double, 6, 6> L;          // scatter = L L^T of the centred tracks
  Eigen::Matrix<double, 6, 1> mean;       // centroid of the tracks
  double sqrt_n = 1;

  template <class T>
  bool operator()(T const* const* p, T* res) const {
    const T* ang = p[0];
    const T* c = p[1];
    using M3 = Eigen::Matrix<T, 3, 3>;
    using V3 = Eigen::Matrix<T, 3, 1>;
    const M3 U = rot_z(ang[0]) * U0.cast<T>(), V = rot_z(ang[1]) * V0.cast<T>(), W = rot_z(ang[2]) * W0.cast<T>();
    M3 core[3];
    for (auto& m : core) m.setZero();
    for (size_t q = 0; q < pattern.size(); ++q) core[pattern[q] / 9]((pattern[q] / 3) % 3, pattern[q] % 3) = c[q];
    M3 Tt[3];
    M3 VcW[3];
    for (int m = 0; m < 3; ++m) VcW[m] = V * core[m] * W.transpose();
    for (int i = 0; i < 3; ++i) Tt[i] = U(i, 0) * VcW[0] + U(i, 1) * VcW[1] + U(i, 2) * VcW[2];
    const V3 e2 = V.col(0), e3 = W.col(0);
    Eigen::Matrix<T, 3, 4> P2, P3;
    const M3 E3 = e3 * e3.transpose() - M3::Identity();
    for (int i = 0; i < 3; ++i) {
      P2.col(i) = Tt[i] * e3;
      P3.col(i) = E3 * (Tt[i].transpose() * e2);
    }
    P2.col(3) = e2;
    P3.col(3) = e3;
    // affine maps x_v = M_v (X1, X2, X4) + t_v for X = (X1, X2, 1, X4)
    Eigen::Matrix<T, 6, 3> M = Eigen::Matrix<T, 6, 3>::Zero();
    Eigen::Matrix<T, 6, 1> t = Eigen::Matrix<T, 6, 1>::Zero();
    M(0, 0) = T(1);
    M(1, 1) = T(1);
    const Eigen::Matrix<T, 3, 4>* Ps[2] = {&P2, &P3};
    for (int v = 0; v < 2; ++v) {
      const auto& P = *Ps[v];
      const T w = P(2, 2);
      for (int r = 0; r < 2; ++r) {
        M(2 + 2 * v + r, 0) = P(r, 0) / w;
        M(2 + 2 * v + r, 1) = P(r, 1) / w;
        M(2 + 2 * v + r, 2) = P(r, 3) / w;
        t(2 + 2 * v + r) = P(r, 2) / w;
      }
    }
    const M3 G = M.transpose() * M;
    const Eigen::Matrix<T, 6, 6> Q = Eigen::Matrix<T, 6, 6>::Identity() - M * G.inverse() * M.transpose();
    const Eigen::Matrix<T, 6, 6> QL = Q * L.cast<T>();
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < 6; ++b) res[6 * a + b] = QL(b, a);
    const Eigen::Matrix<T, 6, 1> d = Q * (mean.cast<T>() - t) * T(sqrt_n);
    for (int a = 0; a < 6; ++a) res[36 + a] = d(a);
    return true;
  }
};

}  // namespace

bool minimal_core_entry(int i, int j, int k) {
  if (j >= 1 && k >= 1) return false;          // e' = V e_1, e'' = W e_1
  if (i == 0) return (j == 0 && k == 0) || (j == 0 && k == 2);  // u1 = e12: Tc_1 = e_1 (W^T e32)^T
  if (i == 1) return !((j == 1 && k == 0) || (j == 0 && k == 1));  // affine: in-plane u2
  return true;
}

MinimalParameterization minimal_parameterization(const CameraTriplet& P) {
  const Eigen::Vector4d C1(0, 0, 0, 1), C2 = camera_centre(P[1]);
  const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ();
  MinimalParameterization mp;
  const Eigen::Vector3d u1 = in_plane_unit(image_of(P[0], C2));  // e12
  const Eigen::Vector3d v1 = in_plane_unit(image_of(P[1], C1));  // e21 = a4
  const Eigen::Vector3d w1 = in_plane_unit(image_of(P[2], C1));  // e31 = b4
  mp.U << u1, ez.cross(u1), ez;
  mp.V << v1, ez, v1.cross(ez);
  mp.W << w1, ez, w1.cross(ez);
  const TrifocalTensor T = unit_trifocal(trifocal_from_cameras(P[0], P[1], P[2]));
  double big = 0;
  for (int i = 0; i < 3; ++i) {
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    for (int m = 0; m < 3; ++m) S += mp.U(m, i) * T[m];
    mp.core[i] = mp.V.transpose() * S * mp.W;
    big = std::max(big, mp.core[i].cwiseAbs().maxCoeff());
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        if (minimal_core_entry(i, j, k)) {
          if (std::fabs(mp.core[i](j, k)) > 1e-9 * big) ++mp.nonzero;
        } else {
          mp.off_pattern = std::max(mp.off_pattern, std::fabs(mp.core[i](j, k)) / big);
          mp.core[i](j, k) = 0;
        }
      }
  return mp;
}

TrifocalTensor trifocal_minimal(const Eigen::MatrixXd& xy) {
  if (xy.rows() < kAffineMinTracks) throw InputError("minimal needs at least 4 tracks");
  const auto H = isotropic_normalization(xy, true);  // common scale: the cost is in pixels
  const Eigen::MatrixXd xn = apply_normalization(xy, H);
  // start: affine-dlt in this frame, its (affine) cameras, and the consistent tensor of those cameras
  const TrifocalTensor T0 = affine_tensor_from_vector(smallest_eigenvector(affine_incidence_normal_matrix(xn)));
  CameraTriplet P = cameras_from_trifocal(T0);
  for (int v = 1; v < 3; ++v) P[v](2, 0) = P[v](2, 1) = P[v](2, 3) = 0;  // exact affine form (rounding)
  const MinimalParameterization mp = minimal_parameterization(P);

  auto* cost = new MinimalCost;
  cost->U0 = mp.U;
  cost->V0 = mp.V;
  cost->W0 = mp.W;
  std::vector<double> core;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        if (minimal_core_entry(i, j, k)) {
          cost->pattern.push_back(9 * i + 3 * j + k);
          core.push_back(mp.core[i](j, k));
        }
  Eigen::Map<Eigen::VectorXd> cv(core.data(), static_cast<Eigen::Index>(core.size()));
  cv.normalize();
  const double n = static_cast<double>(xn.rows());
  cost->mean = xn.colwise().mean().transpose();
  Eigen::MatrixXd centred = xn.rowwise() - cost->mean.transpose();
  Eigen::Matrix<double, 6, 6> S = centred.transpose() * centred;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(S);
  cost->L = es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  cost->sqrt_n = std::sqrt(n);

  double ang[3] = {0, 0, 0};
  auto* fn = new ceres::DynamicAutoDiffCostFunction<MinimalCost, 8>(cost);
  fn->AddParameterBlock(3);
  fn->AddParameterBlock(static_cast<int>(core.size()));
  fn->SetNumResiduals(42);
  ceres::Problem problem;
  problem.AddResidualBlock(fn, nullptr, ang, core.data());
  if (core.size() >= 2)
    problem.SetManifold(core.data(), new ceres::SphereManifold<ceres::DYNAMIC>(static_cast<int>(core.size())));
  ceres::Solver::Options opt;
  opt.linear_solver_type = ceres::DENSE_QR;
  opt.max_num_iterations = 200;
  opt.function_tolerance = 1e-15;
  opt.gradient_tolerance = 1e-20;
  opt.parameter_tolerance = 1e-15;
  opt.max_num_consecutive_invalid_steps = 20;
  opt.num_threads = 1;
  opt.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(opt, &problem, &summary);
  // at the optimum, rounding can make the last trial steps "invalid"; the parameters then hold the last
  // accepted (best) point, which is what we want unless the cost is not finite
  if (!std::isfinite(summary.final_cost) || summary.final_cost > summary.initial_cost)
    throw NumericalError("minimal: optimization failed: " + summary.message);

  // the tensor of the optimized parameters
  const Eigen::Matrix3d U = Eigen::AngleAxisd(ang[0], Eigen::Vector3d::UnitZ()).toRotationMatrix() * mp.U;
  const Eigen::Matrix3d V = Eigen::AngleAxisd(ang[1], Eigen::Vector3d::UnitZ()).toRotationMatrix() * mp.V;
  const Eigen::Matrix3d W = Eigen::AngleAxisd(ang[2], Eigen::Vector3d::UnitZ()).toRotationMatrix() * mp.W;
  TrifocalTensor C;
  for (auto& m : C) m.setZero();
  for (size_t q = 0; q < core.size(); ++q) C[cost->pattern[q] / 9]((cost->pattern[q] / 3) % 3, cost->pattern[q] % 3) = core[q];
  TrifocalTensor Tn;
  for (int i = 0; i < 3; ++i) {
    Tn[i].setZero();
    for (int m = 0; m < 3; ++m) Tn[i] += U(i, m) * (V * C[m] * W.transpose());
  }
  return denormalize_affine_trifocal(Tn, H);
}

}  // namespace tpkit
