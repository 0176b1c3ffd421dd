// GeoTIFF georeferencing of any raster: a UTM and a geographic grid written by write_reference_dem (PixelIsArea,
// tie point at the top-left pixel's corner) read back as the affine map of pixel centres, their pixels taken to
// lon, lat (checked against PROJ's inverse of the UTM zone and against the geographic grid's own degrees), and
// a TIFF without GeoTIFF keys refused naming the file.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/ground/geotiff_georef.hpp"
#include "tpkit/ground/reference_dem.hpp"
#include "utm_dem_fixture.hpp"

using namespace tpkit;

namespace {
std::string scratch(const std::string& name) { return tpkit_test::scratch("geotiff_georef", name); }
}  // namespace

TEST(GeoTiffGeoref, UtmGridPixelCentresAndLonLat) {
  const double e0 = 696015, n0 = 4799985, posting = 30;
  const std::string path = scratch("utm.tif");
  write_reference_dem(path, tpkit_test::utm_raster(e0, n0, posting, 20, 10, [](double, double) { return 5.0; }, "ellipsoid", 0));
  const GeoTiffGeoref g = read_geotiff_georef(path);
  EXPECT_EQ(g.width, 20);
  EXPECT_EQ(g.height, 10);
  EXPECT_EQ(g.crs, "EPSG:32631");
  EXPECT_FALSE(g.geographic);
  // the top-left pixel's centre, not its corner
  EXPECT_NEAR(g.a[0], e0, 1e-9);
  EXPECT_NEAR(g.a[3], n0, 1e-9);
  EXPECT_NEAR(g.a[1], posting, 1e-12);
  EXPECT_NEAR(g.a[5], -posting, 1e-12);
  EXPECT_EQ(g.a[2], 0);
  EXPECT_EQ(g.a[4], 0);
  GeorefToLonLat to_ll(g);
  tpkit_test::Utm31 utm;
  for (const auto& [c, r] : {std::pair<double, double>{0, 0}, {19, 9}, {7.5, 3.25}}) {
    double lon, lat, lon_ref, lat_ref;
    ASSERT_TRUE(to_ll(c, r, lon, lat));
    utm.lonlat(e0 + posting * c, n0 - posting * r, lon_ref, lat_ref);
    EXPECT_NEAR(lon, lon_ref, 1e-9) << c << ' ' << r;
    EXPECT_NEAR(lat, lat_ref, 1e-9) << c << ' ' << r;
    EXPECT_NEAR(lon, 5.4, 0.2);  // east of Marseille: east, north in that order
    EXPECT_NEAR(lat, 43.3, 0.2);
  }
}

TEST(GeoTiffGeoref, GeographicGridIsItsOwnDegrees) {
  DemRaster d;
  d.epsg = 4326;
  d.x0 = -81.66, d.y0 = 30.35, d.dx = 1e-4, d.dy = 2e-4;
  d.width = 8, d.height = 6;
  d.data.assign(48, 1.0f);
  d.tile = 0;
  const std::string path = scratch("geo.tif");
  write_reference_dem(path, d);
  const GeoTiffGeoref g = read_geotiff_georef(path);
  EXPECT_TRUE(g.geographic);
  GeorefToLonLat to_ll(g);
  double lon, lat;
  ASSERT_TRUE(to_ll(3, 5, lon, lat));
  EXPECT_NEAR(lon, -81.66 + 3e-4, 1e-10);
  EXPECT_NEAR(lat, 30.35 - 10e-4, 1e-10);
}

TEST(GeoTiffGeoref, TiffWithoutKeysRefusedNamingTheFile) {
  const std::string path = scratch("plain.tif");
  write_image_u8(path, 4, 4, std::vector<uint8_t>(16, 7));
  try {
    read_geotiff_georef(path);
    FAIL() << "a TIFF without GeoTIFF keys was read as georeferenced";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find("georeferencing"), std::string::npos) << e.what();
  }
}
