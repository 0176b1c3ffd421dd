// See cluster_synth.hpp.
#include "tpkit/cluster_synth.hpp"

#include <algorithm>
#include <random>
#include <vector>

namespace tpkit {

namespace {
Eigen::MatrixX2d add_extra_and_shuffle(const std::vector<Eigen::Vector2d>& pts, int extra, std::mt19937_64& rng) {
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const auto& p : pts) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  std::vector<Eigen::Vector2d> all = pts;
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < extra; ++k) all.emplace_back(lo(0) + u(rng) * (hi(0) - lo(0)), lo(1) + u(rng) * (hi(1) - lo(1)));
  std::shuffle(all.begin(), all.end(), rng);
  Eigen::MatrixX2d m(all.size(), 2);
  for (size_t i = 0; i < all.size(); ++i) m.row(i) = all[i].transpose();
  return m;
}
}  // namespace

ClusterPair synth_cluster_pair(const Eigen::Matrix3d& H, const ClusterSynthOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> u(0, o.extent);
  std::normal_distribution<double> g(0, 1);
  std::vector<Eigen::Vector2d> a, b;
  for (int i = 0; i < o.n; ++i) {
    Eigen::Vector2d p(u(rng), u(rng));
    a.push_back(p);
    Eigen::Vector3d q = H * Eigen::Vector3d(p(0), p(1), 1.0);
    b.emplace_back(q(0) / q(2) + o.noise * g(rng), q(1) / q(2) + o.noise * g(rng));
  }
  std::shuffle(b.begin(), b.end(), rng);
  b.resize(b.size() - static_cast<size_t>(o.missing * o.n + 0.5));
  int extra = static_cast<int>(o.extra * o.n + 0.5);
  ClusterPair r;
  r.A = add_extra_and_shuffle(a, extra, rng);
  r.B = add_extra_and_shuffle(b, extra, rng);
  r.truth = H;
  return r;
}

Eigen::MatrixX2d extent_grid(const Eigen::MatrixX2d& pts) {
  Eigen::Vector2d lo = pts.colwise().minCoeff().transpose(), hi = pts.colwise().maxCoeff().transpose();
  Eigen::MatrixX2d g(25, 2);
  for (int i = 0; i < 25; ++i)
    g.row(i) << lo(0) + (hi(0) - lo(0)) * (i % 5) / 4.0, lo(1) + (hi(1) - lo(1)) * (i / 5) / 4.0;
  return g;
}

}  // namespace tpkit
