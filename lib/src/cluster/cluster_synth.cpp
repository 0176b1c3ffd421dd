// See cluster_synth.hpp.
#include "tpkit/cluster/cluster_synth.hpp"

#include <algorithm>
#include <cmath>
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

Eigen::Matrix3d random_family_homography(double aniso, double proj, double extent, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  const double th = 2 * 3.14159265358979323846 * U(rng), sc = 0.3 * std::pow(10.0, U(rng));
  const double an = 1 + (aniso - 1) * U(rng);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity(), R = Eigen::Matrix3d::Identity(), P = Eigen::Matrix3d::Identity(),
                  C = Eigen::Matrix3d::Identity(), D = Eigen::Matrix3d::Identity();
  C(0, 2) = C(1, 2) = -extent / 2;  // about A's centre, then into B's frame at (1000, 1000)
  D(0, 2) = D(1, 2) = 1000;
  R << std::cos(th), -std::sin(th), 0, std::sin(th), std::cos(th), 0, 0, 0, 1;
  S(0, 0) = sc * std::sqrt(an), S(1, 1) = sc / std::sqrt(an);
  P(2, 0) = proj * (2 * U(rng) - 1) / extent, P(2, 1) = proj * (2 * U(rng) - 1) / extent;
  return D * P * R * S * C;
}

Eigen::MatrixX2d extent_grid(const Eigen::MatrixX2d& pts) {
  Eigen::Vector2d lo = pts.colwise().minCoeff().transpose(), hi = pts.colwise().maxCoeff().transpose();
  Eigen::MatrixX2d g(25, 2);
  for (int i = 0; i < 25; ++i)
    g.row(i) << lo(0) + (hi(0) - lo(0)) * (i % 5) / 4.0, lo(1) + (hi(1) - lo(1)) * (i / 5) / 4.0;
  return g;
}

}  // namespace tpkit
