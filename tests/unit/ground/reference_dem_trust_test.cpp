// Reference DEMs as others write them (issue 50; each case names its item): fixtures are write_reference_dem's
// files with keys or tags changed in place, or written here with libtiff where tpkit's writer has no such layout.
#include <geotiff/geotiff.h>
#include <geotiff/geovalues.h>
#include <geotiff/xtiffio.h>
#include <gtest/gtest.h>
#include <tiffio.h>

#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "../limited_process.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/ground/dem_compare.hpp"
#include "tpkit/ground/reference_dem.hpp"
#include "utm_dem_fixture.hpp"

using namespace tpkit;

namespace {

std::string scratch(const std::string& name) { return tpkit_test::scratch("reference_dem_trust", name); }

// The InputError's message of `f`, "" when it throws none.
std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

double height_at(const ReferenceDem& dem, double lon, double lat) {
  double h = NAN;
  EXPECT_TRUE(dem.height(lon, lat, h)) << dem.path();
  return h;
}

}  // namespace

// Item 8: a float32 DEM whose GDAL_NODATA is "-3.4e+38" (as GDAL writes it): cells of the float -3.4e38 are
// no-data, not heights; the points on them are unknown, and a DEM with none of the points on it is refused.
TEST(ReferenceDemKeys, Float32NodataComparedAsAFloat) {
  const double e0 = 690000, n0 = 4800000;
  DemRaster r = tpkit_test::utm_raster(e0, n0, 30, 400, 400, [](double, double) { return 100.0; }, "ellipsoid", 0);
  r.nodata = -3.4e38f;
  for (long y = 0; y < r.height; ++y)
    for (long x = 200; x < r.width; ++x) r.data[static_cast<size_t>(y * r.width + x)] = NAN;  // the east half void
  const std::string path = scratch("nodata_float.tif");
  write_reference_dem(path, r);
  TIFF* tif = XTIFFOpen(path.c_str(), "r+");  // the tag as GDAL writes it (tag 42113 known: written above)
  ASSERT_NE(tif, nullptr);
  TIFFSetField(tif, 42113, "-3.4e+38");
  XTIFFClose(tif);
  ReferenceDem dem(path);
  tpkit_test::Utm31 utm;
  GroundSample west, east;
  utm.lonlat(e0 + 100 * 30, n0 - 200 * 30, west.lon, west.lat);
  utm.lonlat(e0 + 300 * 30, n0 - 200 * 30, east.lon, east.lat);
  double h;
  EXPECT_NEAR(height_at(dem, west.lon, west.lat), 100, 1e-6);
  EXPECT_FALSE(dem.height(east.lon, east.lat, h)) << h;
  const DemComparison c = compare_to_dem({west, east}, dem);
  EXPECT_EQ(c.all.count, 1);
  EXPECT_EQ(c.unknown, 1);
  const std::string e = refusal([&] { compare_to_dem({east, east}, dem); });
  EXPECT_NE(e.find(path + ": none of the 2 points has a height on it"), std::string::npos) << e;
}

// Item 13: a datum is a keyword or a grid's name; PROJ's optional '@' (no grid when missing), a list, spaces
// and '+' parameters are refused naming the option rather than pasted into the PROJ definition.
TEST(ReferenceDemKeys, DatumOptionIsAGridNameOnly) {
  for (const std::string datum : {"@missing.gtx", "@egm96_15.gtx", "egm96_15.gtx +multiplier=1000", "egm96_15.gtx+multiplier=1000",
                                  "missing.gtx,egm96_15.gtx", "egm96_15.gtx\t"}) {
    const std::string e = refusal([&] { VerticalDatum d(datum); });
    EXPECT_EQ(e.rfind("--dem-datum '" + datum + "': neither ellipsoid, egm96, egm2008 nor a grid's file name", 0), 0u) << e;
  }
  // The grid behind egm96 named by its file, found in PROJ's search path: the same undulation.
  VerticalDatum by_file("egm96_15.gtx"), named("egm96");
  EXPECT_DOUBLE_EQ(by_file.undulation(5.4, 43.3), named.undulation(5.4, 43.3));
}

