// dz statistics against hand-computed figures; compare_to_dem on a plane of known slope; Nuth & Kaab recovering
// a known 3-D shift of points taken from a hilly surface, against a 30 m DEM of that surface in UTM.
#include <gtest/gtest.h>
#include <proj.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <random>
#include <sstream>

#include "tpkit/ground/dem_align.hpp"
#include "tpkit/ground/dem_compare.hpp"
#include "utm_dem_fixture.hpp"

namespace fs = std::filesystem;
using namespace tpkit;

namespace {

std::string scratch(const std::string& name) { return tpkit_test::scratch("dem_align", name); }

using Utm = tpkit_test::Utm31;

// A DEM of surface z(e, n) on a UTM 31N grid, 'posting' m, top-left centre (e0, n0), w x h cells.
std::string write_dem(const std::string& name, double e0, double n0, double posting, long w, long h,
                      const std::function<double(double, double)>& z) {
  const DemRaster r = tpkit_test::utm_raster(e0, n0, posting, w, h, z, "ellipsoid", 128);
  const std::string path = scratch(name);
  write_reference_dem(path, r);
  return path;
}

}  // namespace

TEST(DemCompare, StatisticsByHand) {
  // {1, 2, 3, 4, 10}: mean 4, median 3, |dz - 3| = {2, 1, 0, 1, 7} -> median 1, NMAD 1.4826, RMSE sqrt(130/5).
  const DzStats s = dz_stats({10, 2, 4, 1, 3});
  EXPECT_EQ(s.count, 5);
  EXPECT_DOUBLE_EQ(s.mean, 4);
  EXPECT_DOUBLE_EQ(s.median, 3);
  EXPECT_DOUBLE_EQ(s.nmad, 1.4826);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(26.0));
  // Even count: median of the two middle values.
  EXPECT_DOUBLE_EQ(dz_stats({4, 1, 2, 3}).median, 2.5);
}

TEST(DemCompare, PlaneOfKnownSlopeByClass) {
  // Slope atan(0.15) = 8.53 deg: every point in class 5-10. dz offsets {1, 2, 3, 4, 10} as above.
  const double e0 = 696000, n0 = 4800000;
  const auto z = [&](double e, double n) { return 200 + 0.15 * (e - e0); };
  (void)n0;
  const std::string path = write_dem("plane.tif", e0, n0, 30, 200, 200, z);
  ReferenceDem dem(path);
  Utm utm;
  std::vector<GroundSample> pts;
  const double off[5] = {1, 2, 3, 4, 10};
  for (int i = 0; i < 5; ++i) {
    const double e = e0 + 1000 + 400 * i, n = n0 - 1500 - 300 * i;
    GroundSample p;
    utm.lonlat(e, n, p.lon, p.lat);
    p.h = z(e, n) + off[i];
    pts.push_back(p);
  }
  pts.push_back({100, 10, 0});  // off the DEM
  const DemComparison c = compare_to_dem(pts, dem);
  EXPECT_EQ(c.unknown, 1);
  EXPECT_EQ(c.all.count, 5);
  EXPECT_NEAR(c.all.median, 3, 1e-3);
  EXPECT_NEAR(c.all.nmad, 1.4826, 1e-3);
  EXPECT_NEAR(c.all.rmse, std::sqrt(26.0), 1e-3);
  EXPECT_EQ(c.by_slope[1].count, 5);
  EXPECT_EQ(c.by_slope[0].count + c.by_slope[2].count + c.by_slope[3].count + c.by_slope[4].count, 0);
  std::ostringstream os;
  write_dem_dz(os, {{{"dem", path}}, {c}});
  EXPECT_EQ(os.str().rfind("# tpkit dem-dz 1\n", 0), 0u);
  EXPECT_NE(os.str().find("\n0 2 5 10 5 3"), std::string::npos) << os.str();
}

TEST(DemAlign, RecoversAKnownShift) {
  // Hills of 80-100 m relief and 1.2-2 km wavelength, a 30 m DEM; 3000 points taken from the surface itself at
  // random places, then moved by t = (+7.0 east, -4.0 north, +3.0 up) m: the alignment must give -t.
  const double e0 = 696000, n0 = 4800000;
  const auto z = [&](double e, double n) {
    const double x = e - e0, y = n - n0;
    return 300 + 60 * std::sin(x / 300.0) * std::cos(y / 200.0) + 30 * std::sin((x + y) / 350.0);
  };
  const std::string path = write_dem("hills.tif", e0, n0, 30, 300, 300, z);
  ReferenceDem dem(path);
  Utm utm;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(1000, 8000);
  std::vector<GroundSample> pts;
  // t in the tangent plane at the scene's centre (GroundShift's frame, not UTM's, 1.7 deg apart here).
  GroundShift t;
  t.east = 7;
  t.north = -4;
  t.up = 3;
  utm.lonlat(e0 + 4500, n0 - 4500, t.lon0, t.lat0);
  for (int i = 0; i < 3000; ++i) {
    const double e = e0 + u(rng), n = n0 - u(rng);
    GroundSample p;
    utm.lonlat(e, n, p.lon, p.lat);
    p.h = z(e, n);
    pts.push_back(t.apply(p));  // the point of the surface at (e, n), moved by t
  }
  const DemAlignment a = align_to_dem(pts, dem);
  EXPECT_TRUE(a.converged);
  // Tolerances: the 30 m bilinear DEM of a curved surface (its dz NMAD after alignment is under 0.1 m).
  EXPECT_NEAR(a.shift.east, -t.east, 0.15);
  EXPECT_NEAR(a.shift.north, -t.north, 0.15);
  EXPECT_NEAR(a.shift.up, -t.up, 0.1);
  EXPECT_GT(std::fabs(a.before.all.median), 0.5);
  EXPECT_LT(std::fabs(a.after.all.median), 0.2);
  EXPECT_LT(a.after.all.nmad, a.before.all.nmad / 3);
  // A translation leaves no tilt behind.
  EXPECT_FALSE(a.tilt.significant()) << a.tilt.range_m << " m span";
  EXPECT_LT(std::fabs(a.tilt.east_per_km), 0.05);
  EXPECT_LT(std::fabs(a.tilt.north_per_km), 0.05);

  // The same points with their heights tilted by 0.8 m/km eastward on top of t: the tilt is measured and said
  // (a span of about 0.8 * 7 km = 5.6 m over the points), which no shift removes.
  std::vector<GroundSample> tilted = pts;
  for (GroundSample& p : tilted) {
    double e, n;
    utm.forward(p.lon, p.lat, e, n);
    p.h += 0.8 * (e - (e0 + 4500)) / 1000;
  }
  const DemAlignment b = align_to_dem(tilted, dem);
  EXPECT_TRUE(b.tilt.significant());
  EXPECT_NEAR(b.tilt.east_per_km, 0.8, 0.1);
  EXPECT_NEAR(b.tilt.range_m, 5.6, 0.6);
}
