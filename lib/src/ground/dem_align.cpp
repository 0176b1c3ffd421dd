#include "tpkit/ground/dem_align.hpp"

#include <Eigen/Dense>
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

// The plane dz = c + a e + b n over the points the DEM covers (stage after the shift; see DzTilt).
DzTilt fit_tilt(const std::vector<GroundSample>& moved, const ReferenceDem& dem, double lon0, double lat0) {
  double me, mn;
  metres_per_degree(lat0, me, mn);
  std::vector<Eigen::Vector3d> en_dz;  // e, n (m), dz
  for (const GroundSample& p : moved) {
    double h;
    if (dem.height(p.lon, p.lat, h)) en_dz.emplace_back((p.lon - lon0) * me, (p.lat - lat0) * mn, p.h - h);
  }
  DzTilt t;
  if (en_dz.size() < 10) return t;
  std::vector<double> dz;
  for (const auto& v : en_dz) dz.push_back(v[2]);
  const DzStats st = dz_stats(dz);
  const double gate = 5 * std::max(st.nmad, 0.01);
  std::vector<Eigen::Vector3d> kept;
  for (const auto& v : en_dz)
    if (std::fabs(v[2] - st.median) <= gate) kept.push_back(v);
  Eigen::MatrixXd A(kept.size(), 3);
  Eigen::VectorXd b(kept.size());
  for (size_t i = 0; i < kept.size(); ++i) {
    A.row(i) << 1, kept[i][0] / 1000, kept[i][1] / 1000;
    b[i] = kept[i][2];
  }
  const Eigen::Vector3d x = A.colPivHouseholderQr().solve(b);
  t.east_per_km = x[1];
  t.north_per_km = x[2];
  double lo = INFINITY, hi = -INFINITY;
  std::vector<double> about;
  for (const auto& v : kept) {
    const double plane = x[1] * v[0] / 1000 + x[2] * v[1] / 1000;
    lo = std::min(lo, plane);
    hi = std::max(hi, plane);
    about.push_back(v[2] - x[0] - plane);
  }
  t.range_m = hi - lo;
  t.nmad_m = dz_stats(about).nmad;
  return t;
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
  r.tilt = fit_tilt(moved, dem, r.shift.lon0, r.shift.lat0);
  return r;
}

}  // namespace tpkit
