#include "tpkit/match/affine_fundamental.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>

namespace tpkit {

double AffineFundamental::epipolar_distance2(double x1, double y1, double x2, double y2) const {
  double g = std::hypot(n(0), n(1));
  return g > 0 ? std::abs(residual(x1, y1, x2, y2)) / g : std::abs(residual(x1, y1, x2, y2));
}

Eigen::Matrix3d AffineFundamental::matrix() const {
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  F(0, 2) = n(0);
  F(1, 2) = n(1);
  F(2, 0) = n(2);
  F(2, 1) = n(3);
  F(2, 2) = e;
  return F;
}

bool fit_affine_fundamental(const Eigen::MatrixX4d& xy, const std::vector<int>& idx, AffineFundamental& F) {
  const int m = idx.empty() ? static_cast<int>(xy.rows()) : static_cast<int>(idx.size());
  if (m < AffineFundamental::MINIMUM_SAMPLES) return false;
  auto row = [&](int k) -> Eigen::Vector4d {
    int r = idx.empty() ? k : idx[k];
    return Eigen::Vector4d(xy(r, 2), xy(r, 3), xy(r, 0), xy(r, 1));  // (x2, y2, x1, y1)
  };
  Eigen::Vector4d mean = Eigen::Vector4d::Zero();
  for (int k = 0; k < m; ++k) mean += row(k);
  mean /= m;
  Eigen::Matrix4d C = Eigen::Matrix4d::Zero();
  for (int k = 0; k < m; ++k) {
    Eigen::Vector4d d = row(k) - mean;
    C.noalias() += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(C);
  if (es.info() != Eigen::Success) return false;
  // the normal is the eigenvector of the smallest eigenvalue; degenerate when two are (near) zero
  const Eigen::Vector4d ev = es.eigenvalues();
  if (!(ev(3) > 0) || ev(1) <= 1e-12 * ev(3)) return false;
  F.n = es.eigenvectors().col(0);
  F.e = -F.n.dot(mean);
  // fixed sign for reproducibility
  int big = 0;
  for (int i = 1; i < 4; ++i)
    if (std::abs(F.n(i)) > std::abs(F.n(big))) big = i;
  if (F.n(big) < 0) {
    F.n = -F.n;
    F.e = -F.e;
  }
  return std::isfinite(F.e) && F.n.allFinite();
}

AffineFundamentalResult ransac_affine_fundamental(const Eigen::MatrixX4d& xy, const AffineFundamentalRansac& o) {
  AffineFundamentalResult res;
  const int n = static_cast<int>(xy.rows());
  res.inlier.assign(n, 0);
  if (n < AffineFundamental::MINIMUM_SAMPLES) return res;
  std::mt19937_64 rng(o.seed);
  const double t2 = o.threshold * o.threshold;
  auto score = [&](const AffineFundamental& F, int* count) {
    double s = 0;
    int c = 0;
    for (int r = 0; r < n; ++r) {
      double d = F.residual(xy(r, 0), xy(r, 1), xy(r, 2), xy(r, 3));
      double d2 = d * d;
      if (d2 < t2) {
        s += d2;
        ++c;
      } else {
        s += t2;
      }
    }
    *count = c;
    return s;
  };
  double best = std::numeric_limits<double>::infinity();
  AffineFundamental bestF;
  int best_count = 0;
  long needed = o.max_iterations;
  std::vector<int> sample(4);
  int it = 0;
  for (; it < needed && it < o.max_iterations; ++it) {
    for (int k = 0; k < 4; ++k) {
      for (;;) {
        int r = static_cast<int>(rng() % static_cast<uint64_t>(n));
        if (std::find(sample.begin(), sample.begin() + k, r) == sample.begin() + k) {
          sample[k] = r;
          break;
        }
      }
    }
    AffineFundamental F;
    if (!fit_affine_fundamental(xy, sample, F)) continue;
    int c = 0;
    double s = score(F, &c);
    if (s < best) {
      best = s;
      bestF = F;
      best_count = c;
      double w = static_cast<double>(c) / n;
      double p_fail = 1.0 - std::pow(w, 4);
      if (p_fail <= 0) needed = it + 1;
      else needed = std::min<long>(o.max_iterations, static_cast<long>(std::ceil(std::log(1 - o.confidence) / std::log(p_fail))));
    }
  }
  res.iterations = it;
  if (best_count < AffineFundamental::MINIMUM_SAMPLES) return res;
  // local optimisation: refit on the inliers until the set is stable
  AffineFundamental F = bestF;
  std::vector<int> in;
  for (int round = 0; round < 10; ++round) {
    std::vector<int> cur;
    for (int r = 0; r < n; ++r)
      if (std::pow(F.residual(xy(r, 0), xy(r, 1), xy(r, 2), xy(r, 3)), 2) < t2) cur.push_back(r);
    if (cur == in) break;
    in = cur;
    AffineFundamental G;
    if (!fit_affine_fundamental(xy, in, G)) break;
    F = G;
  }
  res.F = F;
  double ss = 0;
  res.inliers = 0;
  for (int r = 0; r < n; ++r) {
    double d = F.residual(xy(r, 0), xy(r, 1), xy(r, 2), xy(r, 3));
    if (d * d < t2) {
      res.inlier[r] = 1;
      ++res.inliers;
      ss += d * d;
    }
  }
  res.rms = res.inliers ? std::sqrt(ss / res.inliers) : 0;
  res.ok = res.inliers >= AffineFundamental::MINIMUM_SAMPLES;
  return res;
}

}  // namespace tpkit
