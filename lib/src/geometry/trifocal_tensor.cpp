#include "tpkit/geometry/trifocal_tensor.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "tpkit/core/error.hpp"

namespace tpkit {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0, -v(2), v(1), v(2), 0, -v(0), -v(1), v(0), 0;
  return S;
}

TrifocalTensor denormalize_affine_trifocal(const TrifocalTensor& Tn, const std::vector<Eigen::Matrix3d>& H) {
  TrifocalTensor T = transform_trifocal(Tn, H[0].inverse(), H[1].inverse(), H[2].inverse());
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        if (affine_zero_entry(i, j, k)) T[i](j, k) = 0;
  return unit_trifocal(T);
}

Vector27 trifocal_to_vector(const TrifocalTensor& T) {
  Vector27 t;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) t(9 * i + 3 * j + k) = T[i](j, k);
  return t;
}

TrifocalTensor trifocal_from_vector(const Vector27& t) {
  TrifocalTensor T;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) T[i](j, k) = t(9 * i + 3 * j + k);
  return T;
}

bool affine_zero_entry(int i, int j, int k) {
  if (i < 2) return j == 2 || k == 2;  // T_1, T_2: third row and third column
  return j == 2 && k == 2;             // T_3(3,3)
}

const std::array<int, 16>& affine_nonzero_indices() {
  static const std::array<int, 16> idx = [] {
    std::array<int, 16> a{};
    int n = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k)
          if (!affine_zero_entry(i, j, k)) a[n++] = 9 * i + 3 * j + k;
    return a;
  }();
  return idx;
}

TrifocalTensor trifocal_from_cameras(const Camera& P1, const Camera& P2, const Camera& P3) {
  TrifocalTensor T;
  for (int i = 0; i < 3; ++i) {
    Eigen::Matrix<double, 2, 4> a;
    int r = 0;
    for (int q = 0; q < 3; ++q)
      if (q != i) a.row(r++) = P1.row(q);
    double sign = (i % 2 == 0) ? 1.0 : -1.0;
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        Eigen::Matrix4d M;
        M << a, P2.row(j), P3.row(k);
        T[i](j, k) = sign * M.determinant();
      }
  }
  return T;
}

TrifocalTensor transform_trifocal(const TrifocalTensor& T, const Eigen::Matrix3d& H1, const Eigen::Matrix3d& H2,
                                  const Eigen::Matrix3d& H3) {
  Eigen::Matrix3d H1i = H1.inverse();
  TrifocalTensor out;
  for (int i = 0; i < 3; ++i) {
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    for (int a = 0; a < 3; ++a) S += H1i(a, i) * T[a];
    out[i] = H2 * S * H3.transpose();
  }
  return out;
}

TrifocalTensor unit_trifocal(const TrifocalTensor& T) {
  double n2 = 0, big = 0;
  for (const auto& Ti : T) {
    n2 += Ti.squaredNorm();
    for (int q = 0; q < 9; ++q)
      if (std::fabs(Ti.data()[q]) > std::fabs(big)) big = Ti.data()[q];
  }
  if (!(n2 > 0) || !std::isfinite(n2)) throw NumericalError("the trifocal tensor is zero or not finite");
  double s = (big < 0 ? -1.0 : 1.0) / std::sqrt(n2);
  TrifocalTensor out;
  for (int i = 0; i < 3; ++i) out[i] = T[i] * s;
  return out;
}

Eigen::Matrix3d trifocal_incidence(const TrifocalTensor& T, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                                   const Eigen::Vector3d& x3) {
  Eigen::Matrix3d S = x1(0) * T[0] + x1(1) * T[1] + x1(2) * T[2];
  return skew(x2) * S * skew(x3);
}

Eigen::Matrix<double, 4, 27> trifocal_incidence_rows(const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                                                     const Eigen::Vector3d& x3) {
  const Eigen::Matrix3d S2 = skew(x2), S3 = skew(x3);
  Eigen::Matrix<double, 4, 27> A;
  for (int p = 0; p < 2; ++p)
    for (int q = 0; q < 2; ++q) {
      const int r = 2 * p + q;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const double a = x1(i) * S2(p, j);
          for (int k = 0; k < 3; ++k) A(r, 9 * i + 3 * j + k) = a * S3(k, q);
        }
    }
  return A;
}

std::vector<Eigen::Matrix3d> isotropic_normalization(const Eigen::MatrixXd& xy, bool common_scale) {
  const int views = static_cast<int>(xy.cols() / 2);
  const double n = static_cast<double>(xy.rows());
  if (xy.rows() == 0) throw NumericalError("no points to normalize");
  std::vector<Eigen::Matrix3d> H(views);
  std::vector<double> dist(views), cx(views), cy(views);
  for (int v = 0; v < views; ++v) {
    cx[v] = xy.col(2 * v).sum() / n;
    cy[v] = xy.col(2 * v + 1).sum() / n;
    double d = 0;
    for (Eigen::Index r = 0; r < xy.rows(); ++r) d += std::hypot(xy(r, 2 * v) - cx[v], xy(r, 2 * v + 1) - cy[v]);
    dist[v] = d / n;
    if (!(dist[v] > 0) || !std::isfinite(dist[v]))
      throw NumericalError("view " + std::to_string(v + 1) + ": all points coincide (no spread to normalize)");
  }
  double common = std::accumulate(dist.begin(), dist.end(), 0.0) / views;
  for (int v = 0; v < views; ++v) {
    double s = std::sqrt(2.0) / (common_scale ? common : dist[v]);
    H[v] << s, 0, -s * cx[v], 0, s, -s * cy[v], 0, 0, 1;
  }
  return H;
}

Eigen::MatrixXd apply_normalization(const Eigen::MatrixXd& xy, const std::vector<Eigen::Matrix3d>& H) {
  Eigen::MatrixXd out(xy.rows(), xy.cols());
  for (size_t v = 0; v < H.size(); ++v) {
    const double s = H[v](0, 0), tx = H[v](0, 2), ty = H[v](1, 2);
    out.col(2 * v) = (s * xy.col(2 * v)).array() + tx;
    out.col(2 * v + 1) = (s * xy.col(2 * v + 1)).array() + ty;
  }
  return out;
}

void check_trifocal_input(const Eigen::MatrixXd& xy, int min_points, const std::string& method, bool noise_rank_test) {
  if (xy.cols() != 6) throw InputError("trifocal fitting needs tracks with exactly three views (x1 y1 x2 y2 x3 y3)");
  const Eigen::Index n = xy.rows();
  if (n < min_points)
    throw InputError("method " + method + " needs at least " + std::to_string(min_points) + " tracks; got " +
                     std::to_string(n));
  for (Eigen::Index r = 0; r < n; ++r)
    if (!xy.row(r).allFinite()) throw InputError("track record " + std::to_string(r + 1) + " has a non-finite coordinate");
  // duplicated tracks carry no information and make the minimal count a lie
  std::vector<Eigen::Index> order(n);
  std::iota(order.begin(), order.end(), 0);
  auto less = [&](Eigen::Index a, Eigen::Index b) {
    for (int c = 0; c < 6; ++c)
      if (xy(a, c) != xy(b, c)) return xy(a, c) < xy(b, c);
    return a < b;
  };
  std::sort(order.begin(), order.end(), less);
  for (Eigen::Index q = 1; q < n; ++q)
    if ((xy.row(order[q]).array() == xy.row(order[q - 1]).array()).all())
      throw InputError("track records " + std::to_string(std::min(order[q], order[q - 1]) + 1) + " and " +
                       std::to_string(std::max(order[q], order[q - 1]) + 1) + " are the same point (duplicated track)");
  // planar scene (flat terrain): the centred measurement matrix has rank 2
  auto H = isotropic_normalization(xy, true);
  Eigen::MatrixXd W = apply_normalization(xy, H).transpose();  // 6 x n
  Eigen::Matrix<double, 6, 6> C = W * W.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(C);
  Eigen::Matrix<double, 6, 1> lam = es.eigenvalues().reverse().cwiseMax(0.0);  // descending
  const bool rank2 = lam(2) <= 1e-12 * lam(0);
  const bool noise_level = noise_rank_test && n >= 10 && lam(2) < 1.69 * lam(3);  // sigma3 < 1.3 sigma4
  if (rank2 || noise_level)
    throw NumericalError("method " + method +
                         ": the points are coplanar in space (flat terrain, no relief): the centred measurement "
                         "matrix has rank 2 up to noise (sigma3/sigma1 = " +
                         std::to_string(std::sqrt(lam(2) / lam(0))) +
                         "), so the trifocal tensor is not determined");
}

}  // namespace tpkit
