#include "tpkit/geometry/trifocal_dlt.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

#include "tpkit/geometry/camera_recovery.hpp"
#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {

// Constraint enforcement (Hartley & Zisserman §16.3, the linear steps of algorithm 16.2). A
// geometrically valid tensor is T_i = a_i e''^T - e' b_i^T (cameras P' = [A|e'], P'' = [B|e''], a_i, b_i
// the columns of A, B). With the epipoles fixed it is linear in the 18 entries of A and B: t = E p.
// The t minimizing the algebraic error t^T N t subject to ||t|| = 1 in the range of E (rank 15: A and B
// are defined up to A + e' v^T, B + e'' v^T) is the smallest eigenvector of U^T N U, U an orthonormal
// basis of that range. The epipoles are not iterated (that would be the algebraic minimization proper,
// ten times slower for a few percent on the transfer error).
Vector27 solve_given_epipoles(const Eigen::Matrix<double, 27, 27>& N, const Eigen::Vector3d& e2,
                                         const Eigen::Vector3d& e3) {
  // parameters: a_i[j] at 3 i + j, b_i[k] at 9 + 3 i + k
  Eigen::Matrix<double, 27, 18> E = Eigen::Matrix<double, 27, 18>::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        E(9 * i + 3 * j + k, 3 * i + j) += e3(k);
        E(9 * i + 3 * j + k, 9 + 3 * i + k) -= e2(j);
      }
  Eigen::JacobiSVD<Eigen::Matrix<double, 27, 18>> svd(E, Eigen::ComputeFullU);
  int r = 0;
  while (r < 18 && svd.singularValues()(r) > 1e-10 * svd.singularValues()(0)) ++r;
  const Eigen::MatrixXd U = svd.matrixU().leftCols(r);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(U.transpose() * N * U);
  return U * es.eigenvectors().col(0);
}

// The linear tensor's epipoles (null vectors of its T_i), then the constrained tensor for them.
Vector27 enforce_constraints(const Eigen::Matrix<double, 27, 27>& N, const Vector27& t0) {
  const TrifocalEpipoles e = trifocal_epipoles(trifocal_from_vector(t0));
  const Vector27 t = solve_given_epipoles(N, e.e2.normalized(), e.e3.normalized());
  if (!t.allFinite()) throw NumericalError("dlt: constraint enforcement gave a non-finite tensor");
  return t;
}

}  // namespace

TrifocalTensor trifocal_dlt(const Eigen::MatrixXd& xy, bool enforce) {
  if (xy.rows() < kDltMinTracks) throw InputError("dlt needs at least 7 tracks");
  const auto H = isotropic_normalization(xy, false);
  const Eigen::MatrixXd xn = apply_normalization(xy, H);
  // A^T A of the four equations per track without forming A: the rows of one track are
  // x (x) a_p (x) b_q (p, q = 1, 2; a_p rows of [x']_x, b_q columns of [x'']_x), so its contribution is
  // the Kronecker product S1 (x) S2 (x) S3 with S1 = x x^T, S2 = sum_p a_p a_p^T, S3 = sum_q b_q b_q^T.
  // Accumulate the 6 x 6 x 6 sums of products of their unique entries, then assemble the 27 x 27 matrix.
  static const int sym[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  double M[6][6][6] = {};
  for (Eigen::Index r = 0; r < xn.rows(); ++r) {
    const double x = xn(r, 0), y = xn(r, 1), u = xn(r, 2), v = xn(r, 3), s = xn(r, 4), t = xn(r, 5);
    const double S1[6] = {x * x, x * y, x, y * y, y, 1.0};
    const double S2[6] = {1.0, 0.0, -u, 1.0, -v, u * u + v * v};
    const double S3[6] = {1.0, 0.0, -s, 1.0, -t, s * s + t * t};
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < 6; ++b) {
        if (b == 1) continue;
        const double ab = S1[a] * S2[b];
        for (int c = 0; c < 6; ++c) M[a][b][c] += ab * S3[c];
      }
  }
  Eigen::Matrix<double, 27, 27> N;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (int i2 = 0; i2 < 3; ++i2)
          for (int j2 = 0; j2 < 3; ++j2)
            for (int k2 = 0; k2 < 3; ++k2)
              N(9 * i + 3 * j + k, 9 * i2 + 3 * j2 + k2) = M[sym[i][i2]][sym[j][j2]][sym[k][k2]];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 27, 27>> es(N);
  if (es.info() != Eigen::Success) throw NumericalError("dlt: eigen decomposition failed");
  Vector27 t = es.eigenvectors().col(0);
  if (es.eigenvalues()(1) <= 1e-13 * es.eigenvalues()(26))
    throw NumericalError("dlt: the linear system has more than one solution (degenerate track configuration)");
  if (enforce) t = enforce_constraints(N, t);
  const TrifocalTensor Tn = trifocal_from_vector(t);
  return unit_trifocal(transform_trifocal(Tn, H[0].inverse(), H[1].inverse(), H[2].inverse()));
}

}  // namespace tpkit
