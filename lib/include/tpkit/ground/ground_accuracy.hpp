// Accuracy in metres of points whose true ground position is known (GCPs, check points).
//
// Conventions: an error is estimated minus known, in metres east, north, up of the local tangent frame
// (GeographicLib LocalCartesian, WGS 84) at the known point; horizontal error r = sqrt(e^2 + n^2),
// vertical error |u|. Per set of n points:
//   RMSE_e, RMSE_n, RMSE_u = sqrt(mean of the squares); RMSE_r (horizontal) = sqrt(RMSE_e^2 + RMSE_n^2);
//   CE90 = the empirical 90th percentile of r: the ceil(0.9 n)-th smallest r (nearest rank);
//   LE90 = the empirical 90th percentile of |u| (same rank);
//   CE90_normal = 1.5175 * RMSE_r and LE90_normal = 1.6449 * RMSE_u: the same figures for normal,
//   unbiased, circular errors (ASPRS 2014 / NGA: CE90 = 2.1460 * RMSE_e when RMSE_e = RMSE_n, i.e.
//   2.1460 / sqrt(2) = 1.5175 * RMSE_r).
// With few points (check points: 20) the empirical figures are coarse; both are reported.
#pragma once
#include <Eigen/Core>
#include <vector>

namespace tpkit {

// estimated minus known (lon, lat in degrees, h in m), in metres east, north, up at `known`
Eigen::Vector3d enu_error(const Eigen::Vector3d& estimated_llh, const Eigen::Vector3d& known_llh);

struct AccuracyStats {
  long n = 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();  // mean e, n, u error (m): a common shift
  double rmse_e = 0, rmse_n = 0, rmse_u = 0, rmse_r = 0;
  double ce90 = 0, le90 = 0;                       // empirical (see above)
  double ce90_normal = 0, le90_normal = 0;         // from the RMSEs (see above)
};
// NaN figures for an empty set.
AccuracyStats accuracy_stats(const std::vector<Eigen::Vector3d>& enu_errors);

// The nearest-rank p-quantile (0 < p <= 1) of the values: the ceil(p n)-th smallest; NaN when empty.
double nearest_rank_quantile(std::vector<double> values, double p);

}  // namespace tpkit
