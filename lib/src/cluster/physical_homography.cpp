// See physical_homography.hpp.
#include "tpkit/cluster/physical_homography.hpp"

#include <ceres/ceres.h>

#include <cmath>

#include "tpkit/core/error.hpp"

namespace tpkit {

ViewParams ViewParams::from_array(const double* v) {
  ViewParams r;
  r.px = v[0], r.py = v[1], r.rho = v[2], r.alpha = v[3], r.beta = v[4], r.gamma = v[5];
  r.res = v[6], r.theta = v[7], r.cx = v[8], r.cy = v[9];
  return r;
}

std::array<double, kPhysicalParamCount> PhysicalParams::array() const {
  std::array<double, kPhysicalParamCount> a{};
  auto a1 = view[0].array(), a2 = view[1].array();
  for (int i = 0; i < kViewParamCount; ++i) a[i] = a1[i], a[i + kViewParamCount] = a2[i];
  return a;
}

PhysicalParams PhysicalParams::from_array(const double* v) {
  PhysicalParams p;
  p.view[0] = ViewParams::from_array(v);
  p.view[1] = ViewParams::from_array(v + kViewParamCount);
  return p;
}

const std::vector<std::string>& physical_param_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> base = {"px", "py", "rho", "alpha", "beta", "gamma", "res", "theta", "cx", "cy"};
    std::vector<std::string> n;
    for (int v = 1; v <= 2; ++v)
      for (const auto& b : base) n.push_back(b + std::to_string(v));
    return n;
  }();
  return names;
}

int physical_param_index(const std::string& name) {
  const auto& n = physical_param_names();
  for (size_t i = 0; i < n.size(); ++i)
    if (n[i] == name) return static_cast<int>(i);
  return -1;
}

Eigen::Matrix3d normalized_homography(const Eigen::Matrix3d& H) {
  if (std::abs(H(2, 2)) > 1e-12 * H.norm()) return H / H(2, 2);
  return H / H.norm();
}

Eigen::Matrix3d physical_homography(const PhysicalParams& p) {
  auto a = p.array();
  return normalized_homography(physical_homography_t(a.data()));
}

std::string physical_params_problem(const PhysicalParams& p) {
  auto a = p.array();
  const auto& names = physical_param_names();
  for (int i = 0; i < kPhysicalParamCount; ++i)
    if (!std::isfinite(a[i])) return "parameter " + names[i] + " is not finite";
  for (int v = 0; v < 2; ++v) {
    const ViewParams& q = p.view[v];
    std::string s = std::to_string(v + 1);
    if (!(q.rho > 0)) return "rho" + s + " must be > 0 (metres), got " + std::to_string(q.rho);
    if (!(q.beta > 0 && q.beta <= M_PI / 2 + 1e-12))
      return "beta" + s + " (elevation) must be in (0, pi/2] rad, got " + std::to_string(q.beta);
    if (!(q.res > 0)) return "res" + s + " must be > 0 (m/pixel), got " + std::to_string(q.res);
    if (!(std::abs(q.theta) < M_PI / 2 - 1e-6)) return "theta" + s + " must be in (-pi/2, pi/2) rad";
  }
  return "";
}

PhysicalParams paper_physical_params() {
  PhysicalParams p;
  ViewParams& a = p.view[0];
  a.px = 0, a.py = 0, a.rho = 800000, a.alpha = 1.57, a.beta = 0.55, a.gamma = 0, a.res = 20, a.theta = 0.1,
  a.cx = 1, a.cy = 1;
  ViewParams& b = p.view[1];
  b.px = 100, b.py = 100, b.rho = 800000, b.alpha = 0.8, b.beta = 1, b.gamma = 1.57, b.res = 20, b.theta = 0.1,
  b.cx = 1, b.cy = 1;
  return p;
}

PhysicalParams paper_start_params() {
  PhysicalParams p = paper_physical_params();
  p.view[0].px += 200;
  p.view[0].py -= 50;
  p.view[0].alpha -= 0.17;
  p.view[0].beta -= 0.05;
  p.view[0].gamma += 0.5;
  return p;
}

Eigen::Matrix3d paper_eq4_homography() {
  Eigen::Matrix3d H;
  H << 0.248587, 1.779159, 2.327801, -0.917194, -0.090371, 6.597157, -0.000009, -0.000023, 1.000021;
  return H;
}

namespace {
// Residual of one sample point: model(x1) - target(x1) in image-2 pixels.
struct FitResidual {
  double x, y, tx, ty;
  template <class T>
  bool operator()(const T* p, T* r) const {
    Eigen::Matrix<T, 3, 3> H = physical_homography_t(p);
    T u = H(0, 0) * x + H(0, 1) * y + H(0, 2);
    T v = H(1, 0) * x + H(1, 1) * y + H(1, 2);
    T w = H(2, 0) * x + H(2, 1) * y + H(2, 2);
    r[0] = u / w - tx;
    r[1] = v / w - ty;
    return true;
  }
};
}  // namespace

PhysicalParams fit_physical_params(const Eigen::Matrix3d& H, const PhysicalParams& start,
                                   const Eigen::MatrixX2d& sample, bool free_intrinsics, double* rms) {
  auto p = start.array();
  ceres::Problem problem;
  int used = 0;
  for (Eigen::Index i = 0; i < sample.rows(); ++i) {
    Eigen::Vector3d q = H * Eigen::Vector3d(sample(i, 0), sample(i, 1), 1.0);
    if (!(std::abs(q(2)) > 1e-12)) continue;
    auto* f = new ceres::AutoDiffCostFunction<FitResidual, 2, kPhysicalParamCount>(
        new FitResidual{sample(i, 0), sample(i, 1), q(0) / q(2), q(1) / q(2)});
    problem.AddResidualBlock(f, nullptr, p.data());
    ++used;
  }
  if (used < 4) throw NumericalError("fit_physical_params: fewer than 4 usable sample points");
  std::vector<int> fixed;
  if (!free_intrinsics)
    for (int v = 0; v < 2; ++v)
      for (int k = 6; k < 10; ++k) fixed.push_back(v * kViewParamCount + k);
  if (!fixed.empty()) problem.SetManifold(p.data(), new ceres::SubsetManifold(kPhysicalParamCount, fixed));
  // Keep a camera looking down at the plane (physical_params_problem): rho > 0, 0 < beta <= pi/2,
  // res > 0, |theta| < pi/2.
  for (int v = 0; v < 2; ++v) {
    int o = v * kViewParamCount;
    problem.SetParameterLowerBound(p.data(), o + 2, 1.0);
    problem.SetParameterLowerBound(p.data(), o + 4, 1e-3);
    problem.SetParameterUpperBound(p.data(), o + 4, M_PI / 2);
    if (free_intrinsics) {
      problem.SetParameterLowerBound(p.data(), o + 6, 1e-9);
      problem.SetParameterLowerBound(p.data(), o + 7, -1.5);
      problem.SetParameterUpperBound(p.data(), o + 7, 1.5);
    }
  }
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = 200;
  o.function_tolerance = 1e-14;
  o.parameter_tolerance = 1e-14;
  o.gradient_tolerance = 1e-16;
  ceres::Solver::Summary s;
  ceres::Solve(o, &problem, &s);
  if (rms) *rms = std::sqrt(2.0 * s.final_cost / (2.0 * used));
  return PhysicalParams::from_array(p.data());
}

}  // namespace tpkit
