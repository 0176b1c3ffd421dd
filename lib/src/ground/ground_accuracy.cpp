#include "tpkit/ground/ground_accuracy.hpp"

#include <GeographicLib/LocalCartesian.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tpkit {

Eigen::Vector3d enu_error(const Eigen::Vector3d& est, const Eigen::Vector3d& known) {
  GeographicLib::LocalCartesian lc(known[1], known[0], known[2]);
  double e, n, u;
  lc.Forward(est[1], est[0], est[2], e, n, u);
  return {e, n, u};
}

double nearest_rank_quantile(std::vector<double> v, double p) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const size_t rank = static_cast<size_t>(std::ceil(p * static_cast<double>(v.size()) - 1e-9));
  return v[std::min(v.size(), std::max<size_t>(rank, 1)) - 1];
}

AccuracyStats accuracy_stats(const std::vector<Eigen::Vector3d>& err) {
  AccuracyStats s;
  s.n = static_cast<long>(err.size());
  if (err.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    s.mean.setConstant(nan);
    s.rmse_e = s.rmse_n = s.rmse_u = s.rmse_r = s.ce90 = s.le90 = s.ce90_normal = s.le90_normal = nan;
    return s;
  }
  Eigen::Vector3d sq = Eigen::Vector3d::Zero();
  std::vector<double> r, v;
  for (const auto& e : err) {
    s.mean += e;
    sq += e.cwiseProduct(e);
    r.push_back(std::hypot(e[0], e[1]));
    v.push_back(std::fabs(e[2]));
  }
  s.mean /= static_cast<double>(s.n);
  sq /= static_cast<double>(s.n);
  s.rmse_e = std::sqrt(sq[0]);
  s.rmse_n = std::sqrt(sq[1]);
  s.rmse_u = std::sqrt(sq[2]);
  s.rmse_r = std::sqrt(sq[0] + sq[1]);
  s.ce90 = nearest_rank_quantile(r, 0.9);
  s.le90 = nearest_rank_quantile(v, 0.9);
  s.ce90_normal = 1.5175 * s.rmse_r;
  s.le90_normal = 1.6449 * s.rmse_u;
  return s;
}

}  // namespace tpkit
