#include "tpkit/ground/dem_compare.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {
double median_of(std::vector<double>& v) {
  const size_t n = v.size(), m = n / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(m), v.end());
  const double hi = v[m];
  if (n % 2) return hi;
  return (*std::max_element(v.begin(), v.begin() + static_cast<long>(m)) + hi) / 2;
}
}  // namespace

DzStats dz_stats(std::vector<double> dz) {
  DzStats s;
  s.count = static_cast<long>(dz.size());
  if (dz.empty()) return s;
  double sum = 0, sum2 = 0;
  for (double d : dz) {
    sum += d;
    sum2 += d * d;
  }
  s.mean = sum / s.count;
  s.rmse = std::sqrt(sum2 / s.count);
  s.median = median_of(dz);
  for (double& d : dz) d = std::fabs(d - s.median);
  s.nmad = 1.4826 * median_of(dz);
  return s;
}

DemComparison compare_to_dem(const std::vector<GroundSample>& points, const ReferenceDem& dem) {
  DemComparison c;
  std::vector<double> all;
  std::array<std::vector<double>, 5> classes;
  for (const GroundSample& p : points) {
    double h, slope, aspect;
    if (!dem.height(p.lon, p.lat, h) || !dem.slope_aspect(p.lon, p.lat, slope, aspect)) {
      ++c.unknown;
      continue;
    }
    const double dz = p.h - h;
    all.push_back(dz);
    size_t k = 0;
    while (k + 1 < classes.size() && slope >= DemComparison::kSlopeBounds[k + 1]) ++k;
    classes[k].push_back(dz);
  }
  if (all.empty())
    throw InputError(dem.path(), 0, "none of the " + std::to_string(points.size()) +
                                        " points has a height on it (off the DEM, or only no-data where they are)");
  c.all = dz_stats(std::move(all));
  for (size_t k = 0; k < classes.size(); ++k) c.by_slope[k] = dz_stats(std::move(classes[k]));
  return c;
}

void write_dem_dz(std::ostream& os, const DzReport& report) {
  write_header(os, "dem-dz", 1, {}, report.meta,
               {"stage", "class", "slope_min", "slope_max", "count", "median", "nmad", "rmse", "mean"});
  for (size_t s = 0; s < report.stages.size(); ++s) {
    const DemComparison& c = report.stages[s];
    for (size_t k = 0; k <= c.by_slope.size(); ++k) {
      const DzStats& d = k == 0 ? c.all : c.by_slope[k - 1];
      const double lo = k == 0 ? 0 : DemComparison::kSlopeBounds[k - 1], hi = k == 0 ? 90 : DemComparison::kSlopeBounds[k];
      write_record(os, {static_cast<double>(s), static_cast<double>(k), lo, hi, static_cast<double>(d.count), d.median,
                        d.nmad, d.rmse, d.mean});
    }
  }
}

std::string describe_dem_comparison(const DemComparison& c, const std::string& prefix) {
  std::ostringstream os;
  auto line = [&](const std::string& what, const DzStats& d) {
    os << prefix << what << ": " << d.count << " points";
    if (d.count) {
      os << ", dz median " << format_figure(d.median) << " m, NMAD " << format_figure(d.nmad) << " m, RMSE "
         << format_figure(d.rmse) << " m, mean " << format_figure(d.mean) << " m";
    }
    os << "\n";
  };
  line("all", c.all);
  for (size_t k = 0; k < c.by_slope.size(); ++k)
    line("slope " + format_figure(DemComparison::kSlopeBounds[k]) + "-" + format_figure(DemComparison::kSlopeBounds[k + 1]) +
             " deg",
         c.by_slope[k]);
  if (c.unknown) os << prefix << c.unknown << " points off the DEM or on its voids (left out)\n";
  return os.str();
}

}  // namespace tpkit
