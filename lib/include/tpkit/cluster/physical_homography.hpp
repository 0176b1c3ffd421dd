// The image-to-image homography of a planar ground scene seen by two pinhole satellites, expressed by
// the "physical parameters" of Navy et al. (2005), section 4 (eq. 5-8).
//
// Ground frame (O, i, j, k): the scene is the plane z = 0, x and y in metres, k pointing up.
// Each image v = 1, 2 has ten parameters, in this order (index in ViewParams::p / in the 20-vector
// of PhysicalParams: view 1 = 0..9, view 2 = 10..19):
//   0 px, 1 py   target point P (metres, ground frame)
//   2 rho        distance P-S (metres)
//   3 alpha      local azimuth of the satellite seen from P, from the ground x axis towards y (rad)
//   4 beta       elevation of the satellite above the ground plane (rad), 0 < beta <= pi/2
//   5 gamma      rotation of the image about the viewing axis k' (rad), extrinsic
//   6 res        resolution (metres per pixel), intrinsic
//   7 theta      angle of the pixel sides (rad; 0 for square pixels), intrinsic
//   8 cx, 9 cy   image centre relative to the optical centre (pixels), intrinsic
// The model (our reading of section 4, stated in man/cluster-homog.1):
//   S  = P + rho (cos b cos a, cos b sin a, sin b)
//   k' = (P - S) / rho                                  (viewing axis, from S to P)
//   i'p = i projected along the vertical k onto the plane normal to k', normalized
//   j'p = k' x i'p                                      (right-handed)
//   i' = cos g i'p + sin g j'p,  j' = -sin g i'p + cos g j'p
//   camera coordinates X' = N^-1 (X - S), N = [i' j' k']; pixel ~ A X' with A of eq. 7
//   A = [rho/res, -rho tan(theta)/res, cx; 0, rho/(res cos theta), cy; 0, 0, 1]
// so that ground (x, y, 1) -> pixel: G = A N^T [e1 e2 -S], and image 1 -> image 2: H = G2 G1^-1
// (pixels x = column, y = row; x2 ~ H x1).
// With the paper's section 5 values and P2 = (100, +100) m this reproduces eq. 4 to ~5e-4 per
// coefficient; the printed P2 = (100, -100) gives h13 = -6.89 instead of 2.33 (a sign typo).
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace tpkit {

constexpr int kViewParamCount = 10;
constexpr int kPhysicalParamCount = 20;

struct ViewParams {
  double px = 0, py = 0, rho = 800000, alpha = 0, beta = 1.5707963267948966, gamma = 0;
  double res = 1, theta = 0, cx = 0, cy = 0;
  std::array<double, kViewParamCount> array() const { return {px, py, rho, alpha, beta, gamma, res, theta, cx, cy}; }
  static ViewParams from_array(const double* v);
};

struct PhysicalParams {
  ViewParams view[2];
  std::array<double, kPhysicalParamCount> array() const;
  static PhysicalParams from_array(const double* v);
};

// Names of the 20 parameters ("px1", "py1", "rho1", "alpha1", "beta1", "gamma1", "res1", "theta1",
// "cx1", "cy1", then the same with 2); index_of returns -1 for an unknown name.
const std::vector<std::string>& physical_param_names();
int physical_param_index(const std::string& name);

// Ground (x, y, 1) in metres -> image pixel (homogeneous) of one view; v points to its 10 parameters.
template <class T>
Eigen::Matrix<T, 3, 3> ground_to_image(const T* v) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  using std::tan;
  using V3 = Eigen::Matrix<T, 3, 1>;
  const T &px = v[0], &py = v[1], &rho = v[2], &a = v[3], &b = v[4], &g = v[5], &res = v[6], &th = v[7];
  V3 dir(cos(b) * cos(a), cos(b) * sin(a), sin(b));  // unit vector from P to S
  V3 S(px + rho * dir(0), py + rho * dir(1), rho * dir(2));
  V3 k = -dir;
  // i projected along the vertical onto the plane normal to k: i + t e_z with (i + t e_z).k = 0.
  V3 ip(T(1), T(0), -k(0) / k(2));
  ip /= sqrt(ip.squaredNorm());
  V3 jp = k.cross(ip);
  T cg = cos(g), sg = sin(g);
  V3 i1 = cg * ip + sg * jp;
  V3 j1 = -sg * ip + cg * jp;
  Eigen::Matrix<T, 3, 3> Rt;  // N^T: rows i', j', k'
  Rt.row(0) = i1.transpose();
  Rt.row(1) = j1.transpose();
  Rt.row(2) = k.transpose();
  Eigen::Matrix<T, 3, 3> M;  // [e1 e2 -S]
  M.col(0) = V3(T(1), T(0), T(0));
  M.col(1) = V3(T(0), T(1), T(0));
  M.col(2) = -S;
  Eigen::Matrix<T, 3, 3> A;
  A << rho / res, -rho * tan(th) / res, v[8], T(0), rho / (res * cos(th)), v[9], T(0), T(0), T(1);
  return A * Rt * M;
}

// x2 ~ H x1 (pixels of image 1 -> pixels of image 2); p points to the 20 parameters. Not normalized.
template <class T>
Eigen::Matrix<T, 3, 3> physical_homography_t(const T* p) {
  Eigen::Matrix<T, 3, 3> G1 = ground_to_image(p), G2 = ground_to_image(p + kViewParamCount);
  return G2 * G1.inverse();
}

// The same in doubles, scaled so that H(2, 2) = 1 (or Frobenius norm 1 when H(2, 2) is ~0).
Eigen::Matrix3d physical_homography(const PhysicalParams& p);

// Checks that the parameters describe a camera looking down at the plane: rho > 0, 0 < beta <= pi/2,
// res > 0, |theta| < pi/2, all finite. Returns "" or the reason.
std::string physical_params_problem(const PhysicalParams& p);

// The paper's section 5 capture conditions (with P2 = (100, +100) m, see above) and its eq. 4.
PhysicalParams paper_physical_params();
// The paper's section 6 starting point: the section 5 values with P1 + (200, -50) m, alpha1 - 0.17,
// beta1 - 0.05, gamma1 + 0.5 (the perturbation the benchmarks and tests start from).
PhysicalParams paper_start_params();
Eigen::Matrix3d paper_eq4_homography();

// Parameters -> H is physical_homography(); H -> parameters: least squares (Ceres) of the free
// parameters, starting from `start`, so that the model's H maps sample points of image 1 (pixels)
// where `H` maps them. `free_intrinsics` frees the 8 intrinsic parameters too (20 instead of 12).
// Returns the fitted parameters; `rms` (if given) gets the RMS transfer difference in pixels.
PhysicalParams fit_physical_params(const Eigen::Matrix3d& H, const PhysicalParams& start,
                                   const Eigen::MatrixX2d& sample_pixels, bool free_intrinsics, double* rms = nullptr);

// Normalizes H so that H(2,2) = 1 when possible (else Frobenius norm 1).
Eigen::Matrix3d normalized_homography(const Eigen::Matrix3d& H);

}  // namespace tpkit
