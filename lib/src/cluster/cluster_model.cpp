// See cluster_model.hpp.
#include "tpkit/cluster/cluster_model.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "tpkit/cluster/cluster_cost.hpp"
#include "tpkit/cluster/cluster_optimize.hpp"
#include "tpkit/cluster/physical_homography.hpp"

namespace tpkit {

const char* cluster_model_name(ClusterModel m) {
  switch (m) {
    case ClusterModel::Similarity: return "similarity";
    case ClusterModel::Affine: return "affine";
    case ClusterModel::Homography: break;
  }
  return "homography";
}

int cluster_model_points(ClusterModel m) {
  return m == ClusterModel::Similarity ? 2 : m == ClusterModel::Affine ? 3 : 4;
}

namespace {

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// No three of the points collinear, relative to their largest squared distance.
bool spread(const Eigen::Vector2d* q, int s) {
  double span2 = 0;
  for (int a = 0; a < s; ++a)
    for (int b = a + 1; b < s; ++b) span2 = std::max(span2, (q[a] - q[b]).squaredNorm());
  if (!(span2 > 0)) return false;
  for (int a = 0; a < s; ++a)
    for (int b = a + 1; b < s; ++b)
      for (int c = b + 1; c < s; ++c)
        if (!(std::fabs(cross2(q[b] - q[a], q[c] - q[a])) > 1e-9 * span2)) return false;
  return true;
}

}  // namespace

bool cluster_model_frame(ClusterModel m, const Eigen::MatrixX2d& P, const int* idx, Eigen::Matrix3d& M, bool mirrored) {
  const int s = cluster_model_points(m);
  Eigen::Vector2d q[4];
  for (int k = 0; k < s; ++k) q[k] = P.row(idx[k]).transpose();
  if (!spread(q, s)) return false;
  switch (m) {
    case ClusterModel::Similarity: {
      const Eigen::Vector2d d = q[1] - q[0];
      if (mirrored) M << d.x(), d.y(), q[0].x(), d.y(), -d.x(), q[0].y(), 0, 0, 1;
      else M << d.x(), -d.y(), q[0].x(), d.y(), d.x(), q[0].y(), 0, 0, 1;
      return true;
    }
    case ClusterModel::Affine:
      M << q[0].x(), q[1].x(), q[2].x(), q[0].y(), q[1].y(), q[2].y(), 1, 1, 1;
      return true;
    case ClusterModel::Homography: {
      Eigen::Matrix3d C;
      for (int k = 0; k < 3; ++k) C.col(k) << q[k].x(), q[k].y(), 1.0;
      const Eigen::Vector3d lambda = C.partialPivLu().solve(Eigen::Vector3d(q[3].x(), q[3].y(), 1.0));
      M = C * lambda.asDiagonal();
      return M.allFinite();
    }
  }
  return false;
}

Eigen::Matrix3d fit_cluster_model(const ClusterCost& cost, ClusterModel m, const Eigen::Matrix3d& H,
                                  const std::vector<std::pair<int, int>>& pairs) {
  const int s = cluster_model_points(m);
  if (static_cast<int>(pairs.size()) < s) return H;
  if (m == ClusterModel::Homography) return fit_on_pairs(cost, H, pairs);
  const Eigen::MatrixX2d &A = cost.a(), &B = cost.b();
  const Eigen::Index n = static_cast<Eigen::Index>(pairs.size());
  Eigen::MatrixXd src(2, n), dst(2, n);  // dynamic sizes: GCC 12 warns falsely inside umeyama on 2 x N
  for (Eigen::Index k = 0; k < n; ++k) {
    src.col(k) = A.row(pairs[static_cast<size_t>(k)].first).transpose();
    dst.col(k) = B.row(pairs[static_cast<size_t>(k)].second).transpose();
  }
  Eigen::Matrix3d out = Eigen::Matrix3d::Identity();
  if (m == ClusterModel::Similarity) {
    // Umeyama keeps the orientation; a mirror image is fitted as the similarity of x-flipped A points
    const bool mirrored = H.topLeftCorner<2, 2>().determinant() < 0;
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
    if (mirrored) F(0, 0) = -1, src.row(0) *= -1;
    out = Eigen::umeyama(src, dst, true) * F;
  } else {
    // affine: centred linear least squares, [x' y'] = L [x y] + t
    const Eigen::Vector2d ca = src.rowwise().mean(), cb = dst.rowwise().mean();
    const Eigen::MatrixX2d X = (src.colwise() - ca).transpose(), Y = (dst.colwise() - cb).transpose();
    const Eigen::Matrix2d Lt = X.colPivHouseholderQr().solve(Y);  // Y = X L^T
    const Eigen::Matrix2d L = Lt.transpose();
    out.topLeftCorner<2, 2>() = L;
    out.topRightCorner<2, 1>() = cb - L * ca;
  }
  return out.allFinite() ? out : H;
}

bool fit_cluster_model_to_matches(const ClusterCost& cost, ClusterModel m, const Eigen::Matrix3d& H0, Eigen::Matrix3d& out,
                                  int max_rounds) {
  const size_t least = static_cast<size_t>(cluster_model_points(m)) + 1;
  Eigen::Matrix3d H = H0;
  bool fitted = false;
  std::vector<std::pair<int, int>> prev;
  for (int round = 0; round < max_rounds; ++round) {
    const std::vector<MutualPair> mutual = mutual_pairs(cost, H);
    if (mutual.size() < least) break;
    std::vector<double> ds;
    for (const MutualPair& mp : mutual) ds.push_back(mp.d);
    std::nth_element(ds.begin(), ds.begin() + static_cast<long>(ds.size() / 2), ds.end());
    // inliers: within 3 robust sigmas of the mutual distances (a lower model than the map that found the
    // pairs misses them by more, and its gate widens with them)
    const double gate = std::max(3 * 1.4826 * ds[ds.size() / 2], 1e-3);
    std::vector<std::pair<int, int>> key;
    for (const MutualPair& mp : mutual)
      if (mp.d <= gate) key.emplace_back(mp.ia, mp.ib);
    if (key.size() < least || key == prev) break;
    prev = key;
    H = fit_cluster_model(cost, m, H, key);
    fitted = true;
  }
  if (fitted) out = normalized_homography(H);
  return fitted;
}

}  // namespace tpkit
