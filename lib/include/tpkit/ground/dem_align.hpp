// Co-registration of ground points to a reference DEM, Nuth & Kaab (2011): for points shifted by t (east,
// north, up; m) from the surface, dz = h - DEM = tan(slope) * |t_h| * cos(aspect - b) + t_up, aspect the
// DEM's downhill azimuth and b the shift's. Each iteration fits dz / tan(slope) = a cos(b - aspect) + c
// (residuals weighted by tan(slope), i.e. in metres of dz, Cauchy loss; Ceres) for the horizontal update, then
// the vertical one as the median dz after it; stops when the horizontal update is below `tolerance_m` or after
// `max_iterations`. Points on slopes below `min_slope_deg` or beyond 5 NMAD of the median dz are left out of
// the fit. The result is the shift to ADD to the points (the opposite of t) to fit the DEM: east/north in metres
// in the tangent plane at the points' centre (converted to degrees there), up in metres.
#pragma once
#include <algorithm>
#include <vector>

#include "tpkit/ground/dem_compare.hpp"

namespace tpkit {

struct DemAlignOptions {
  int max_iterations = 10;
  double tolerance_m = 0.01;
  double min_slope_deg = 2;
};

struct GroundShift {
  double east = 0, north = 0, up = 0;  // m
  double lon0 = 0, lat0 = 0;           // where east/north convert to degrees (the points' centre)
  double dlon() const;                 // east in degrees of lon at lat0
  double dlat() const;                 // north in degrees of lat at lat0
  GroundSample apply(const GroundSample& p) const;
};

// What a translation leaves: the plane dz = c + a e + b n fitted (least squares, points within 5 NMAD of the
// median) to dz after the alignment, e and n metres east and north of the centre. A block adjusted without
// ground control is often tilted (its height error grows across it) rather than shifted; no shift removes a
// tilt, and on slopes a tilt pulls the horizontal shift. `range_m` is the plane's span over the points
// (max - min of a e + b n), `nmad_m` the NMAD of dz about the plane (the DEM's noise and the points').
struct DzTilt {
  double east_per_km = 0, north_per_km = 0;  // a, b in m of dz per km
  double range_m = 0, nmad_m = 0;
  // A tilt worth saying: its span exceeds the scatter about it and 0.5 m.
  bool significant() const { return range_m > std::max(0.5, nmad_m); }
};

struct DemAlignment {
  GroundShift shift;
  DemComparison before, after;
  DzTilt tilt;  // of dz after the alignment
  int iterations = 0;
  bool converged = false;
  long used = 0;  // points in the last fit
};
// NumericalError when fewer than 20 points have a DEM height on slopes above min_slope_deg.
DemAlignment align_to_dem(const std::vector<GroundSample>& points, const ReferenceDem& dem,
                          const DemAlignOptions& options = {});

}  // namespace tpkit
