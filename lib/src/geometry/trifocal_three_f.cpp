#include "tpkit/geometry/trifocal_three_f.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {


const int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};

std::string short_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// 8-point on normalized coordinates of views a, b: x_a^T F x_b = 0.
Eigen::Matrix3d eight_point(const Eigen::MatrixXd& xn, int a, int b) {
  Eigen::Matrix<double, 9, 9> N = Eigen::Matrix<double, 9, 9>::Zero();
  for (Eigen::Index r = 0; r < xn.rows(); ++r) {
    const Eigen::Vector3d p = track_point(xn, r, a), q = track_point(xn, r, b);
    Eigen::Matrix<double, 9, 1> row;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) row(3 * i + j) = p(i) * q(j);
    N.selfadjointView<Eigen::Lower>().rankUpdate(row);
  }
  N = N.selfadjointView<Eigen::Lower>();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> es(N);
  if (es.eigenvalues()(1) <= 1e-13 * es.eigenvalues()(8))
    throw NumericalError("three-f: the 8-point system of views " + std::to_string(a + 1) + "-" + std::to_string(b + 1) +
                         " has more than one solution");
  Eigen::Matrix3d F;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) F(i, j) = es.eigenvectors()(3 * i + j, 0);
  return F;
}

Eigen::Vector3d unit_epipole(double t, double p) {
  return Eigen::Vector3d(std::cos(p) * std::cos(t), std::cos(p) * std::sin(t), std::sin(p));
}

using Params = Eigen::Matrix<double, 31, 1>;

Eigen::Matrix3d F_of(const Params& p, int f) {
  Eigen::Matrix3d F;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) F(i, j) = p(9 * f + 3 * i + j);
  return F;
}

// Orthonormal basis (3 x 2) of the plane orthogonal to v.
Eigen::Matrix<double, 3, 2> complement(const Eigen::Vector3d& v) {
  Eigen::JacobiSVD<Eigen::Matrix<double, 1, 3>> svd(v.transpose(), Eigen::ComputeFullV);
  return svd.matrixV().rightCols<2>();
}

struct Bases {
  Eigen::Matrix<double, 3, 2> plane1, col23, row23;
};

Bases bases_at(const Params& p) {
  const Eigen::Matrix3d F12 = F_of(p, 0), F23 = F_of(p, 2);
  const Eigen::Vector3d e23 = unit_epipole(p(27), p(28));
  Bases b;
  b.plane1 = complement(F12 * e23);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(F23, Eigen::ComputeFullU | Eigen::ComputeFullV);
  b.col23 = svd.matrixU().leftCols<2>();
  b.row23 = svd.matrixV().leftCols<2>();
  return b;
}

Eigen::Vector3d right_null(const Eigen::Matrix3d& F) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullV);
  return svd.matrixV().col(2);
}

constexpr int kConstraints = 13;
using ConstraintVector = Eigen::Matrix<double, kConstraints, 1>;

ConstraintVector constraints(const Params& p, const Bases& b) {
  ConstraintVector g;
  const Eigen::Matrix3d F12 = F_of(p, 0), F13 = F_of(p, 1), F23 = F_of(p, 2);
  const Eigen::Vector3d e23 = unit_epipole(p(27), p(28)), e32 = unit_epipole(p(29), p(30));
  g(0) = F12.determinant();
  g(1) = F13.determinant();
  g(2) = F23.determinant();
  g(3) = F12.squaredNorm() - 1;
  g(4) = F13.squaredNorm() - 1;
  g(5) = F23.squaredNorm() - 1;
  const Eigen::Vector3d c = (F12 * e23).cross(F13 * e32);  // epipolar-plane constraint (eq. 2a/3)
  g.segment<2>(6) = b.plane1.transpose() * c;
  g.segment<2>(8) = b.col23.transpose() * (F23 * e32);              // eq. 4: F23 e32 = 0
  g.segment<2>(10) = b.row23.transpose() * (F23.transpose() * e23);  // eq. 4: F23^T e23 = 0
  // the third compatibility condition (H&Z def. 15.6), which eq. 2a/3 lack: in view 2 the epipolar line
  // of e31 (camera 1 in view 3) passes through e21 (camera 1 in view 2): e21^T F23 e31 = 0
  g(12) = right_null(F12).dot(F23 * right_null(F13));
  return g;
}


// The Gauss-Helmert normal equations of the three condition equations per track, linearized at the
// adjusted observations: for each track the six coordinates are first moved onto the three epipolar
// conditions of F (the per-track least-squares correction v, iterated from the observations: the
// condition equations are bilinear, kCorrectionPasses passes converge to rounding), then
//   w~ = w(x + v) - B v,  B = dw/dx at x + v,  A = dw/dF at x + v,
// and JtJ = sum A^T (B B^T)^-1 A, Jtr = sum A^T (B B^T)^-1 w~, cost = sum w~^T (B B^T)^-1 w~ (= sum |v|^2,
// the squared distance of the observations to the three conditions, at convergence). Linearizing at the
// observations instead (w, B, A at x: the Sampson-weighted, iteratively reweighted fit) has a bias of
// order sigma^2 that does not shrink with n: it made three-f's transfer error 1.6 (tp-synth-like) to 2.4
// (coplanar directions) times ml's at 1000 tracks (issue 15 section 5).
struct Normal {
  Eigen::Matrix<double, 31, 31> JtJ;
  Params Jtr;
  double cost = 0;
};
constexpr int kCorrectionPasses = 4;

Normal normal_at(const Params& q, const Eigen::MatrixXd& xn) {
  Normal nm;
  nm.JtJ.setZero();
  nm.Jtr.setZero();
  const Eigen::Matrix3d F[3] = {F_of(q, 0), F_of(q, 1), F_of(q, 2)};
  for (Eigen::Index r = 0; r < xn.rows(); ++r) {
    const Eigen::Vector3d xo[3] = {track_point(xn, r, 0), track_point(xn, r, 1), track_point(xn, r, 2)};
    Eigen::Vector3d x[3] = {xo[0], xo[1], xo[2]};
    Eigen::Matrix<double, 6, 1> v = Eigen::Matrix<double, 6, 1>::Zero();
    Eigen::Vector3d w;
    Eigen::Matrix<double, 3, 6> B;
    Eigen::Matrix<double, 9, 1> a9[3];  // dw_c / d(F_c entries): the only non-zero block of row c
    Eigen::Matrix3d Winv;
    bool usable = true;
    for (int pass = 0; pass < kCorrectionPasses && usable; ++pass) {
      B.setZero();
      for (int c = 0; c < 3; ++c) {
        const int a = kPairs[c][0], b = kPairs[c][1];
        w(c) = x[a].dot(F[c] * x[b]);
        const Eigen::Vector3d ga = F[c] * x[b], gb = F[c].transpose() * x[a];
        B(c, 2 * a) = ga(0);
        B(c, 2 * a + 1) = ga(1);
        B(c, 2 * b) = gb(0);
        B(c, 2 * b + 1) = gb(1);
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) a9[c](3 * i + j) = x[a](i) * x[b](j);
      }
      w -= B * v;  // the misclosure of the observations, linearized at x + v
      Eigen::LLT<Eigen::Matrix3d> llt(B * B.transpose());
      usable = llt.info() == Eigen::Success;  // a track at an epipole carries no condition
      if (!usable) break;
      Winv = llt.solve(Eigen::Matrix3d::Identity());
      if (pass + 1 < kCorrectionPasses) {
        v = -B.transpose() * (Winv * w);
        for (int k = 0; k < 3; ++k) x[k] = xo[k] + Eigen::Vector3d(v(2 * k), v(2 * k + 1), 0);
      }
    }
    if (!usable) continue;
    const Eigen::Vector3d Ww = Winv * w;
    for (int c = 0; c < 3; ++c) {
      for (int c2 = 0; c2 <= c; ++c2) nm.JtJ.block<9, 9>(9 * c, 9 * c2).noalias() += Winv(c, c2) * a9[c] * a9[c2].transpose();
      nm.Jtr.segment<9>(9 * c) += Ww(c) * a9[c];
    }
    nm.cost += w.dot(Ww);
  }
  for (int c = 0; c < 3; ++c)
    for (int c2 = 0; c2 < c; ++c2) nm.JtJ.block<9, 9>(9 * c2, 9 * c) = nm.JtJ.block<9, 9>(9 * c, 9 * c2).transpose();
  return nm;
}

// Levenberg-Marquardt-damped KKT steps of the linearized constrained problem, accepted when the merit
// cost + rho |g| decreases. Scale-free stopping: the F are unit-norm and the epipoles angles, so the
// parameters and the constraints are O(1) whatever the pixels; the cost is measured in units of the
// noise, sigma^2 ~ cost / (3 n): done when a step (accepted or not) changes the merit by less than
// kChi2Tolerance of that unit (the estimate is then within ~0.03 of its standard error of the optimum;
// a tolerance relative to the whole cost instead needed more iterations the more tracks there were).
constexpr int kMaxAdjustIterations = 100;
constexpr double kChi2Tolerance = 1e-3;
constexpr double kStepTolerance = 1e-10;        // step (parameter units, O(1)) below this: done
constexpr double kConstraintTolerance = 1e-10;  // |g| of unit-norm F's

Params adjust_three_f(const Eigen::MatrixXd& xn, Params p) {
  Normal cur = normal_at(p, xn);
  const double rho = 1e6 * std::max(cur.cost, 1e-300) + 1e-6;
  double merit = cur.cost + rho * constraints(p, bases_at(p)).norm();
  double mu = 1e-6;
  for (int it = 0; it < kMaxAdjustIterations && mu < 1e12; ++it) {
    const Bases b = bases_at(p);
    const ConstraintVector g = constraints(p, b);
    Eigen::Matrix<double, kConstraints, 31> G;
    for (int c = 0; c < 31; ++c) {
      const double h = 1e-7 * std::max(1.0, std::fabs(p(c)));
      Params pp = p, pm = p;
      pp(c) += h;
      pm(c) -= h;
      G.col(c) = (constraints(pp, b) - constraints(pm, b)) / (2 * h);
    }
    const double dmax = cur.JtJ.diagonal().maxCoeff();
    Eigen::Matrix<double, 31 + kConstraints, 31 + kConstraints> K;
    K.setZero();
    // the cost block scaled to O(1) like the constraint rows: unscaled (entries growing with n), the
    // solve lost the constraints to rounding (|g| stalled at 4e-9 for 10^4 tracks, 6e-7 for 10^5, and
    // the merit's rho |g| then rejected step after step)
    K.topLeftCorner<31, 31>() = cur.JtJ / dmax;
    K.topLeftCorner<31, 31>().diagonal() += mu * (cur.JtJ.diagonal().array() / dmax + 1e-9).matrix();
    K.block<31, kConstraints>(0, 31) = G.transpose();
    K.block<kConstraints, 31>(31, 0) = G;
    Eigen::Matrix<double, 31 + kConstraints, 1> rhs;
    rhs.head<31>() = -cur.Jtr / dmax;
    rhs.tail<kConstraints>() = -g;
    const Params dp = K.colPivHouseholderQr().solve(rhs).head<31>();
    if (!dp.allFinite()) throw NumericalError("three-f: the constrained adjustment diverged");
    if (dp.norm() < kStepTolerance) break;
    const Params np = p + dp;
    const Normal nn = normal_at(np, xn);
    const double nmerit = nn.cost + rho * constraints(np, bases_at(np)).norm();
    const double unit = cur.cost / (3.0 * static_cast<double>(xn.rows()));  // ~ sigma^2, normalized units
    const bool flat = std::fabs(merit - nmerit) <= kChi2Tolerance * unit && g.norm() < kConstraintTolerance;
    if (nmerit <= merit) {
      p = np;
      cur = nn;
      merit = nmerit;
      mu = std::max(1e-12, mu / 4);
    } else {
      mu *= 8;
    }
    if (flat) break;  // converged: nothing left to gain at the noise's scale and the constraints hold
  }
  return p;
}
}  // namespace

double three_f_epipolar_angle(const Eigen::Matrix3d& F12, const Eigen::Matrix3d& F13, const Eigen::Matrix3d& F23,
                              const Eigen::Vector3d c[3]) {
  // in view v, the epipolar lines of the other two views' points c (homogeneous lines, normals first)
  auto angle = [](const Eigen::Vector3d& l, const Eigen::Vector3d& m) {
    const Eigen::Vector2d u = l.head<2>().normalized(), w = m.head<2>().normalized();
    return std::asin(std::min(1.0, std::fabs(u.x() * w.y() - u.y() * w.x()))) * 180 / 3.14159265358979323846;
  };
  const double a1 = angle(F12 * c[1], F13 * c[2]);                          // view 1: x1^T F12 x2 = 0
  const double a2 = angle(F12.transpose() * c[0], F23 * c[2]);              // view 2
  const double a3 = angle(F13.transpose() * c[0], F23.transpose() * c[1]);  // view 3
  return std::min({a1, a2, a3});
}

double three_f_epipolar_angle(const ThreeFundamental& f, const Eigen::MatrixXd& xy) {
  Eigen::Vector3d c[3];
  for (int v = 0; v < 3; ++v) c[v] << xy.col(2 * v).mean(), xy.col(2 * v + 1).mean(), 1;
  return three_f_epipolar_angle(f.F12, f.F13, f.F23, c);
}

ThreeFundamental three_fundamental_linear(const Eigen::MatrixXd& xy) {
  if (xy.rows() < kThreeFMinTracks) throw InputError("three-f needs at least 8 tracks");
  const auto H = isotropic_normalization(xy, false);
  const Eigen::MatrixXd xn = apply_normalization(xy, H);
  Eigen::Matrix3d F[3];
  for (int q = 0; q < 3; ++q) {
    const int a = kPairs[q][0], b = kPairs[q][1];
    F[q] = H[a].transpose() * eight_point(xn, a, b) * H[b];  // x_a^T H_a^T F^ H_b x_b
    F[q] /= F[q].norm();
  }
  return {F[0], F[1], F[2]};
}

TrifocalTensor trifocal_three_f(const Eigen::MatrixXd& xy, double min_angle_deg, ThreeFReport* report) {
  if (xy.rows() < kThreeFMinTracks) throw InputError("three-f needs at least 8 tracks");
  const auto H = isotropic_normalization(xy, true);  // common scale: weights in pixels
  const Eigen::MatrixXd xn = apply_normalization(xy, H);
  // 1. linear
  const ThreeFundamental lin = three_fundamental_linear(xn);
  Params p;
  const Eigen::Matrix3d F0[3] = {lin.F12, lin.F13, lin.F23};
  for (int f = 0; f < 3; ++f)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) p(9 * f + 3 * i + j) = F0[f](i, j);
  {
    const Eigen::Vector3d e32 = right_null(lin.F23), e23 = right_null(lin.F23.transpose());
    p(27) = std::atan2(e23(1), e23(0));
    p(28) = std::asin(std::max(-1.0, std::min(1.0, e23(2))));
    p(29) = std::atan2(e32(1), e32(0));
    p(30) = std::asin(std::max(-1.0, std::min(1.0, e32(2))));
  }
  // 2. constrained adjustment (Gauss-Helmert)
  p = adjust_three_f(xn, p);
  // 3. tensor from the adjusted geometry, unless the centres are (nearly) collinear
  const Eigen::Matrix3d F12 = F_of(p, 0), F13 = F_of(p, 1), F23 = F_of(p, 2);
  {
    const Eigen::Vector3d origin(0, 0, 1);  // the centroid of every view in the normalized frame
    const Eigen::Vector3d c[3] = {origin, origin, origin};
    const double angle = three_f_epipolar_angle(F12, F13, F23, c);
    const double min_angle = min_angle_deg;
    if (report) {
      report->epipolar_angle_deg = angle;
      report->min_angle_deg = min_angle;
    }
    if (min_angle > 0 && !(angle >= min_angle))
      throw NumericalError("three-f: the epipolar lines of two views meet in the third at " + short_number(angle) +
                           " deg, below " + short_number(min_angle) + " deg: the camera centres are (nearly) collinear (viewing directions in one plane, as in a "
                           "single-pass acquisition), where three fundamental matrices do not determine the third "
                           "camera; use ml or affine-dlt");
  }
  const Eigen::Matrix3d F21 = F12.transpose(), F31 = F13.transpose(), F32 = F23.transpose();
  const Eigen::Vector3d e21 = right_null(F12), e31 = right_null(F13);
  Camera P1 = Camera::Zero(), P2, P3_0 = Camera::Zero();
  P1.leftCols<3>().setIdentity();
  P2 << skew(e21) * F21, e21;
  P3_0.leftCols<3>() = skew(e31) * F31;
  const Eigen::Matrix4d K0 = P3_0.transpose() * F32 * P2;
  const Eigen::Matrix4d S = K0 + K0.transpose();
  const Eigen::Vector4d gv = P2.transpose() * F32.transpose() * e31;
  Eigen::Matrix<double, 10, 4> A = Eigen::Matrix<double, 10, 4>::Zero();
  Eigen::Matrix<double, 10, 1> rhs;
  int row = 0;
  for (int a = 0; a < 4; ++a)
    for (int c = a; c < 4; ++c) {
      // (y g^T + g y^T)(a, c) = y_a g_c + g_a y_c
      A(row, a) += gv(c);
      A(row, c) += gv(a);
      rhs(row) = -S(a, c);
      ++row;
    }
  const Eigen::Vector4d y = A.colPivHouseholderQr().solve(rhs);
  Camera P3 = P3_0 + e31 * y.transpose();
  if (!P2.allFinite() || !P3.allFinite()) throw NumericalError("three-f: the cameras of the adjusted geometry are not finite");
  const TrifocalTensor Tn = trifocal_from_cameras(P1, P2, P3);
  return unit_trifocal(transform_trifocal(Tn, H[0].inverse(), H[1].inverse(), H[2].inverse()));
}

}  // namespace tpkit
