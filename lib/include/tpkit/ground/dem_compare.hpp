// Heights of ground points against a reference DEM, as ASP geodiff and xdem report them: dz = h - DEM(lon,
// lat) (m, both above the WGS 84 ellipsoid), over all points and by slope class (slope of the DEM's bilinear
// surface at the point, degrees: [0,5) [5,10) [10,20) [20,40) [40,90]).
// Statistics: count, mean, median, NMAD = 1.4826 median|dz - median| (a robust standard deviation), RMSE =
// sqrt(mean dz^2). Points where the DEM is unknown (off it, voids) are counted apart.
#pragma once
#include <array>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include "tpkit/core/text_table.hpp"
#include "tpkit/ground/reference_dem.hpp"

namespace tpkit {

struct GroundSample {
  double lon = 0, lat = 0, h = 0;  // degrees WGS 84, m above the ellipsoid
};

struct DzStats {
  long count = 0;
  double mean = NAN, median = NAN, nmad = NAN, rmse = NAN;
};
DzStats dz_stats(std::vector<double> dz);

struct DemComparison {
  static constexpr std::array<double, 6> kSlopeBounds = {0, 5, 10, 20, 40, 90};  // degrees
  DzStats all;
  std::array<DzStats, 5> by_slope;
  long unknown = 0;  // points the DEM gives no height for
};
// InputError naming the DEM when it gives none of the points a height: statistics of nothing are no comparison.
DemComparison compare_to_dem(const std::vector<GroundSample>& points, const ReferenceDem& dem);

// A dem-dz file (tpkit-formats(5)): one record per (stage, class): stage 0 before alignment, 1 after (only 0
// without one); class 0 all points, 1..5 the slope classes. `meta` holds the DEM, its datum and any shift.
struct DzReport {
  Meta meta;
  std::vector<DemComparison> stages;
};
void write_dem_dz(std::ostream& os, const DzReport& report);
// One line per stage and class for a person (stderr).
std::string describe_dem_comparison(const DemComparison& c, const std::string& prefix);

}  // namespace tpkit
