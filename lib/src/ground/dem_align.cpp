#include "tpkit/ground/dem_align.hpp"

#include <ceres/ceres.h>

#include <cmath>

#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {

constexpr double kRad = M_PI / 180;
constexpr double kA = 6378137.0, kE2 = 6.69437999014e-3;  // WGS 84

// Metres per degree of lon and of lat at latitude lat (radii of curvature of WGS 84).
void metres_per_degree(double lat, double& east, double& north) {
  const double s = std::sin(lat * kRad), w = std::sqrt(1 - kE2 * s * s);
  east = kA / w * std::cos(lat * kRad) * kRad;
  north = kA * (1 - kE2) / (w * w * w) * kRad;
}

// The N&K cosine in metres of dz: tan(slope) (p cos(aspect) + q sin(aspect)) + c = dz, with p = a cos b,
// q = a sin b (the (a, b) of the paper in Cartesian form, no wrap-around of b).
struct CosineResidual {
  double tan_slope, aspect, dz;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    r[0] = T(tan_slope) * (x[0] * std::cos(aspect) + x[1] * std::sin(aspect)) + x[2] - T(dz);
    return true;
  }
};

struct Sample {
  double tan_slope, aspect, dz;
};

// dz, slope and aspect of every point the DEM covers, the points moved by `shift`.
std::vector<Sample> samples(const std::vector<GroundSample>& points, const ReferenceDem& dem, const GroundShift& shift) {
  std::vector<Sample> out;
  for (const GroundSample& p0 : points) {
    const GroundSample p = shift.apply(p0);
    double h, slope, aspect;
    if (!dem.height(p.lon, p.lat, h) || !dem.slope_aspect(p.lon, p.lat, slope, aspect)) continue;
    out.push_back({std::tan(slope * kRad), aspect * kRad, p.h - h});
  }
  return out;
}

// Horizontal offset t (east, north; m) of the points from the surface: the robust cosine fit.
void fit_cosine(const std::vector<Sample>& s, const DemAlignOptions& o, double& te, double& tn, long& used) {
  std::vector<double> dz;
  for (const Sample& x : s) dz.push_back(x.dz);
  const DzStats st = dz_stats(dz);
  const double tmin = std::tan(o.min_slope_deg * kRad), gate = 5 * std::max(st.nmad, 0.01);
  double x[3] = {0, 0, st.median};
  ceres::Problem problem;
  used = 0;
  for (const Sample& v : s) {
    if (v.tan_slope < tmin || std::fabs(v.dz - st.median) > gate) continue;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CosineResidual, 1, 3>(new CosineResidual{v.tan_slope, v.aspect, v.dz}),
                             new ceres::CauchyLoss(std::max(st.nmad, 0.01)), x);
    ++used;
  }
  if (used < 20) throw NumericalError("DEM alignment: " + std::to_string(used) + " points on slopes above " +
                                      format_figure(o.min_slope_deg) + " deg with a DEM height (20 needed)");
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = 50;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  // dz = -grad(h) . t + t_up and grad(h) = -tan(slope) (sin aspect, cos aspect): p = t_north, q = t_east.
  tn = x[0];
  te = x[1];
}

}  // namespace

double GroundShift::dlon() const {
  double e, n;
  metres_per_degree(lat0, e, n);
  return east / e;
}
double GroundShift::dlat() const {
  double e, n;
  metres_per_degree(lat0, e, n);
  return north / n;
}
GroundSample GroundShift::apply(const GroundSample& p) const { return {p.lon + dlon(), p.lat + dlat(), p.h + up}; }

DemAlignment align_to_dem(const std::vector<GroundSample>& points, const ReferenceDem& dem, const DemAlignOptions& options) {
  DemAlignment r;
  double lon = 0, lat = 0;
  for (const GroundSample& p : points) {
    lon += p.lon;
    lat += p.lat;
  }
  if (!points.empty()) {
    r.shift.lon0 = lon / points.size();
    r.shift.lat0 = lat / points.size();
  }
  r.before = compare_to_dem(points, dem);
  for (r.iterations = 1; r.iterations <= options.max_iterations; ++r.iterations) {
    // Stage 1: horizontal update from the points as shifted so far; stage 2: vertical by the median dz.
    double te, tn;
    fit_cosine(samples(points, dem, r.shift), options, te, tn, r.used);
    r.shift.east -= te;
    r.shift.north -= tn;
    std::vector<double> dz;
    for (const Sample& s : samples(points, dem, r.shift)) dz.push_back(s.dz);
    r.shift.up -= dz_stats(dz).median;
    if (std::hypot(te, tn) < options.tolerance_m) {
      r.converged = true;
      break;
    }
  }
  r.iterations = std::min(r.iterations, options.max_iterations);
  std::vector<GroundSample> moved;
  for (const GroundSample& p : points) moved.push_back(r.shift.apply(p));
  r.after = compare_to_dem(moved, dem);
  return r;
}

}  // namespace tpkit
