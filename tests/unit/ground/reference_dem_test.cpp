// Reference DEM: a UTM DEM written by write_reference_dem and read back at known points (its plane z = a + b E
// + c N is reproduced exactly by bilinear sampling), EGM96 undulation at a known place, nodata, off-DEM points,
// on-demand tiles with a cache smaller than the DEM, and errors naming the file.
#include <gtest/gtest.h>
#include <proj.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "tpkit/core/error.hpp"
#include "tpkit/ground/reference_dem.hpp"
#include "utm_dem_fixture.hpp"

namespace fs = std::filesystem;
using namespace tpkit;

namespace {

std::string scratch(const std::string& name) { return tpkit_test::scratch("reference_dem", name); }

// WGS 84 lon, lat -> UTM 31N easting, northing.
void to_utm31(double lon, double lat, double& e, double& n) { tpkit_test::Utm31().forward(lon, lat, e, n); }

// A plane on a UTM 31N grid east of Marseille (lon 5.35-5.57, lat 43.2-43.33): z = 100 + 0.01 (E - E0) -
// 0.02 (N - N0), 30 m posting.
struct PlaneDem {
  double e0 = 696000, n0 = 4800000, dx = 30;
  long w = 400, h = 400;
  double z(double e, double n) const { return 100 + 0.01 * (e - e0) - 0.02 * (n - n0); }
  DemRaster raster(const std::string& datum, int tile) const {
    return tpkit_test::utm_raster(e0, n0, dx, w, h, [this](double e, double n) { return z(e, n); }, datum, tile);
  }
};

}  // namespace

TEST(ReferenceDem, UtmDemReadBackAtKnownPoints) {
  PlaneDem p;
  for (int tile : {0, 64}) {
    const std::string path = scratch("plane_" + std::to_string(tile) + ".tif");
    write_reference_dem(path, p.raster("ellipsoid", tile));
    ReferenceDem dem(path);
    EXPECT_EQ(dem.crs(), "EPSG:32631");
    EXPECT_NEAR(dem.posting_m(), 30, 1e-9);
    // Points well inside: lon/lat picked, their UTM coordinates from PROJ, height of the plane there.
    for (double lon : {5.45, 5.5, 5.55})
      for (double lat : {43.25, 43.28}) {
        double e, n;
        to_utm31(lon, lat, e, n);
        double h, g[2];
        ASSERT_TRUE(dem.height(lon, lat, h, g)) << lon << " " << lat;
        EXPECT_NEAR(h, p.z(e, n), 2e-3) << tile;
        // Gradient: 0.01 m/m east, -0.02 m/m north, in m per degree (about 81 km per degree of lon here).
        double e1, n1, e2, n2;
        to_utm31(lon + 1e-3, lat, e1, n1);
        to_utm31(lon, lat + 1e-3, e2, n2);
        EXPECT_NEAR(g[0], (p.z(e1, n1) - p.z(e, n)) / 1e-3, 0.5);
        EXPECT_NEAR(g[1], (p.z(e2, n2) - p.z(e, n)) / 1e-3, 0.5);
      }
  }
}

TEST(ReferenceDem, Egm96HeightsBecomeEllipsoidal) {
  // EGM96 undulation at (lat 43.3, lon 5.4): 49.4356 m by PROJ's egm96_15.gtx; EPSG:4979 -> EPSG:4326+5773
  // (EGM96 height) gives 100 m ellipsoidal = 50.5644 m above the geoid, the same N.
  VerticalDatum egm96("egm96");
  EXPECT_NEAR(egm96.undulation(5.4, 43.3), 49.4356, 1e-3);
  PlaneDem p;
  p.e0 = 690000;  // covers lon 5.4 (E 694669)
  const std::string path = scratch("plane_egm96.tif"), bare = scratch("plane_no_vertical_keys.tif");
  write_reference_dem(path, p.raster("egm96", 128));
  write_reference_dem(bare, p.raster("ellipsoid", 128));
  ReferenceDem ell(bare), geo(path, {"egm96"});
  double h1, h2;
  ASSERT_TRUE(ell.height(5.4, 43.3, h1));
  ASSERT_TRUE(geo.height(5.4, 43.3, h2));
  EXPECT_NEAR(h2 - h1, 49.4356, 1e-3);
}

TEST(ReferenceDem, NodataAndOffDemAreUnknown) {
  PlaneDem p;
  DemRaster r = p.raster("ellipsoid", 0);
  // A void of one cell at column 150, row 100.
  r.data[static_cast<size_t>(100 * p.w + 150)] = NAN;
  const std::string path = scratch("void.tif");
  write_reference_dem(path, r);
  ReferenceDem dem(path);
  // The void's lon/lat: inverse of its UTM position through PROJ.
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* raw = proj_create_crs_to_crs(ctx, "EPSG:4326", "EPSG:32631", nullptr);
  PJ* pj = proj_normalize_for_visualization(ctx, raw);
  auto lonlat = [&](double e, double n, double& lon, double& lat) {
    const PJ_COORD q = proj_trans(pj, PJ_INV, proj_coord(e, n, 0, 0));
    lon = q.lp.lam;
    lat = q.lp.phi;
  };
  double lon, lat, h;
  lonlat(p.e0 + 150.3 * p.dx, p.n0 - 100.4 * p.dx, lon, lat);
  EXPECT_FALSE(dem.height(lon, lat, h));
  lonlat(p.e0 + 149.5 * p.dx, p.n0 - 99.5 * p.dx, lon, lat);  // a cell of the void's neighbours
  EXPECT_FALSE(dem.height(lon, lat, h));
  lonlat(p.e0 + 148.5 * p.dx, p.n0 - 100.5 * p.dx, lon, lat);  // clear of it
  EXPECT_TRUE(dem.height(lon, lat, h));
  lonlat(p.e0 - 10, p.n0 - 100 * p.dx, lon, lat);  // west of the first column's centre
  EXPECT_FALSE(dem.height(lon, lat, h));
  lonlat(p.e0 + 100 * p.dx, p.n0 - (p.h - 1) * p.dx - 1, lon, lat);  // south of the last row
  EXPECT_FALSE(dem.height(lon, lat, h));
  EXPECT_FALSE(dem.height(100, 10, h));  // far away
  proj_destroy(pj);
  proj_destroy(raw);
  proj_context_destroy(ctx);
}

TEST(ReferenceDem, TilesReadOnDemandWithinTheCache) {
  // 1024 x 1024 cells in 64 x 64 tiles (256 tiles, 4 MiB); a cache of 8 tiles (128 KiB).
  PlaneDem p;
  p.w = p.h = 1024;
  p.dx = 10;
  const std::string path = scratch("tiled.tif");
  write_reference_dem(path, p.raster("ellipsoid", 64));
  ReferenceDem dem(path, {"ellipsoid", 8 * 64 * 64 * sizeof(float)});
  double e, n, h;
  to_utm31(5.5, 43.27, e, n);
  ASSERT_TRUE(dem.height(5.5, 43.27, h));
  EXPECT_NEAR(h, p.z(e, n), 2e-3);
  EXPECT_LE(dem.blocks_read(), 4u);  // only the tiles around the point
  // A walk across the whole DEM: every answer right, never more than 8 tiles held.
  for (int i = 0; i < 200; ++i) {
    const double lon = 5.45 + 0.07 * i / 199.0, lat = 43.29 - 0.045 * i / 199.0;
    to_utm31(lon, lat, e, n);
    ASSERT_TRUE(dem.height(lon, lat, h)) << i;
    {
      EXPECT_NEAR(h, p.z(e, n), 2e-3);
    }
    EXPECT_LE(dem.blocks_cached(), 8u);
  }
  EXPECT_GT(dem.blocks_read(), 8u);
}

TEST(ReferenceDem, ErrorsNameTheFile) {
  const std::string plain = scratch("plain.txt");
  std::ofstream(plain) << "not a tiff\n";
  try {
    ReferenceDem dem(plain);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(plain), std::string::npos);
  }
  PlaneDem p;
  const std::string path = scratch("plane_grid.tif");
  write_reference_dem(path, p.raster("ellipsoid", 0));
  try {
    ReferenceDem dem(path, {"egm2008"});
    // PROJ-data may carry EGM2008; then the datum is usable and nothing to check here.
    double h;
    EXPECT_TRUE(dem.height(5.5, 43.28, h));
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("egm08_25"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  try {
    ReferenceDem dem(path, {scratch("no_such_grid.gtx")});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_grid.gtx"), std::string::npos) << e.what();
  }
}
