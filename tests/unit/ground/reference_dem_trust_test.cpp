// Reference DEMs as others write them (issue 50; each case names its item): fixtures are write_reference_dem's
// files with keys or tags changed in place, or written here with libtiff where tpkit's writer has no such layout.
#include <geotiff/geotiff.h>
#include <geotiff/geovalues.h>
#include <geotiff/xtiffio.h>
#include <gtest/gtest.h>
#include <proj.h>
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

// A plane z = 100 + 0.01 (E - E0) on a UTM 31N grid around lon 5.4, lat 43.3 (30 m posting, strips), heights
// above `datum` (its vertical keys written by write_reference_dem).
std::string plane(const std::string& name, const std::string& datum) {
  const double e0 = 690000, n0 = 4800000;
  const std::string path = scratch(name);
  write_reference_dem(path, tpkit_test::utm_raster(e0, n0, 30, 400, 400, [&](double e, double) { return 100 + 0.01 * (e - e0); },
                                                   datum, 0));
  return path;
}

// Sets (value > 0) or deletes (value 0) GeoKeys of a GeoTIFF in place.
void set_keys(const std::string& path, const std::vector<std::pair<geokey_t, int>>& keys) {
  TIFF* tif = XTIFFOpen(path.c_str(), "r+");
  ASSERT_NE(tif, nullptr);
  GTIF* gtif = GTIFNew(tif);
  for (const auto& [key, value] : keys) GTIFKeySet(gtif, key, TYPE_SHORT, value ? 1 : 0, value);
  GTIFWriteKeys(gtif);
  GTIFFree(gtif);
  XTIFFClose(tif);
}

double height_at(const ReferenceDem& dem, double lon, double lat) {
  double h = NAN;
  EXPECT_TRUE(dem.height(lon, lat, h)) << dem.path();
  return h;
}

// A geographic (EPSG:4326) float32 GeoTIFF DEM of n x n cells of 1e-4 degree, the top-left cell's centre at
// lon 5, lat 44, height = row index; deflated, in one strip (rows_per_strip = n) or one tile (tile = n).
void write_one_block_dem(const std::string& path, long n, bool tiled) {
  TIFF* tif = XTIFFOpen(path.c_str(), "w");
  ASSERT_NE(tif, nullptr);
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(n));
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(n));
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 32);
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
  TIFFSetField(tif, TIFFTAG_ZIPQUALITY, 1);
  double scale[3] = {1e-4, 1e-4, 0}, tie[6] = {0, 0, 0, 5 - 0.5e-4, 44 + 0.5e-4, 0};
  TIFFSetField(tif, TIFFTAG_GEOPIXELSCALE, 3, scale);
  TIFFSetField(tif, TIFFTAG_GEOTIEPOINTS, 6, tie);
  GTIF* gtif = GTIFNew(tif);
  GTIFKeySet(gtif, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeGeographic);
  GTIFKeySet(gtif, GTRasterTypeGeoKey, TYPE_SHORT, 1, RasterPixelIsArea);
  GTIFKeySet(gtif, GeographicTypeGeoKey, TYPE_SHORT, 1, 4326);
  GTIFWriteKeys(gtif);
  GTIFFree(gtif);
  bool ok = true;
  if (tiled) {
    TIFFSetField(tif, TIFFTAG_TILEWIDTH, static_cast<uint32_t>(n));
    TIFFSetField(tif, TIFFTAG_TILELENGTH, static_cast<uint32_t>(n));
    std::vector<float> tile(static_cast<size_t>(n * n));
    for (long r = 0; r < n; ++r) std::fill_n(tile.begin() + r * n, n, static_cast<float>(r));
    ok = TIFFWriteEncodedTile(tif, 0, tile.data(), static_cast<tmsize_t>(tile.size() * sizeof(float))) >= 0;
  } else {
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, static_cast<uint32_t>(n));
    std::vector<float> row(static_cast<size_t>(n));
    for (long r = 0; r < n && ok; ++r) {
      std::fill(row.begin(), row.end(), static_cast<float>(r));
      ok = TIFFWriteScanline(tif, row.data(), static_cast<uint32_t>(r), 0) == 1;
    }
  }
  XTIFFClose(tif);
  ASSERT_TRUE(ok);
}

}  // namespace

// Item 7: EGM96 heights (VerticalCSTypeGeoKey 5773, as GDAL writes EPSG:4326+5773 and write_reference_dem
// writes "egm96") are taken as EGM96 without a datum option: the same heights as with "egm96", N = 49.4356 m
// above those of the same raster with no vertical keys (ellipsoidal).
TEST(ReferenceDemKeys, VerticalCrsKeyGivesTheDatum) {
  const std::string keyed = plane("egm96.tif", "egm96"), bare = plane("bare.tif", "ellipsoid");
  ReferenceDem from_keys(keyed), named(keyed, {"egm96"}), ellipsoidal(bare);
  EXPECT_EQ(from_keys.datum(), "egm96");
  EXPECT_EQ(ellipsoidal.datum(), "ellipsoid");
  EXPECT_NEAR(height_at(from_keys, 5.4, 43.3) - height_at(ellipsoidal, 5.4, 43.3), 49.4356, 1e-3);
  EXPECT_DOUBLE_EQ(height_at(from_keys, 5.4, 43.3), height_at(named, 5.4, 43.3));
  // Without vertical keys a named datum is taken as given.
  ReferenceDem bare_egm96(bare, {"egm96"});
  EXPECT_DOUBLE_EQ(height_at(bare_egm96, 5.4, 43.3), height_at(from_keys, 5.4, 43.3));
}

// Item 7: a datum option that disagrees with the keys is refused, naming both.
TEST(ReferenceDemKeys, DisagreeingDatumRefused) {
  const std::string keyed = plane("egm96_refused.tif", "egm96");
  for (const std::string datum : {"ellipsoid", "egm2008"}) {
    const std::string e = refusal([&] { ReferenceDem dem(keyed, {datum}); });
    EXPECT_NE(e.find(keyed + ": --dem-datum " + datum + " disagrees with the GeoTIFF keys' vertical CRS EPSG:5773 (egm96)"),
              std::string::npos)
        << e;
  }
  // Keys of WGS 84 ellipsoidal heights (5030) refuse egm96.
  const std::string ell = plane("ellipsoidal_keys.tif", "ellipsoid");
  set_keys(ell, {{VerticalCSTypeGeoKey, 5030}});
  EXPECT_EQ(ReferenceDem(ell).datum(), "ellipsoid");
  EXPECT_NE(refusal([&] { ReferenceDem dem(ell, {"egm96"}); }).find("disagrees"), std::string::npos);
}

// Item 7: the vertical datum key alone (VerticalDatumGeoKey 5171, EGM96 geoid) names the datum too; a vertical
// CRS tpkit does not name (NAVD88 height, 5703) needs its grid named, and is then taken as named.
TEST(ReferenceDemKeys, VerticalDatumKeyAndUnknownCrs) {
  const std::string by_datum = plane("datum_key.tif", "ellipsoid");
  set_keys(by_datum, {{VerticalDatumGeoKey, 5171}});
  EXPECT_EQ(ReferenceDem(by_datum).datum(), "egm96");
  const std::string navd = plane("navd88.tif", "ellipsoid");
  set_keys(navd, {{VerticalCSTypeGeoKey, 5703}});
  const std::string e = refusal([&] { ReferenceDem dem(navd); });
  EXPECT_NE(e.find("vertical CRS EPSG:5703"), std::string::npos) << e;
  EXPECT_NE(e.find("--dem-datum"), std::string::npos) << e;
  EXPECT_EQ(ReferenceDem(navd, {"egm96"}).datum(), "egm96");
}

// Item 7: heights in US survey feet (VerticalUnitsGeoKey 9003) come back in metres, and so does the slope.
TEST(ReferenceDemKeys, VerticalUnitsConvertedToMetres) {
  const std::string metres = plane("metres.tif", "ellipsoid"), feet = plane("feet.tif", "ellipsoid");
  set_keys(feet, {{VerticalUnitsGeoKey, 9003}});
  ReferenceDem m(metres), f(feet);
  const double ft = 1200.0 / 3937;
  EXPECT_NEAR(f.vertical_unit_m(), ft, 1e-12);
  EXPECT_NEAR(height_at(f, 5.4, 43.3), ft * height_at(m, 5.4, 43.3), 1e-6);
  double sm, am, sf, af;
  ASSERT_TRUE(m.slope_aspect(5.4, 43.3, sm, am));
  ASSERT_TRUE(f.slope_aspect(5.4, 43.3, sf, af));
  EXPECT_NEAR(std::tan(sf * M_PI / 180), ft * std::tan(sm * M_PI / 180), 1e-6);
  // A unit code EPSG does not know is refused.
  set_keys(feet, {{VerticalUnitsGeoKey, 9999}});
  EXPECT_NE(refusal([&] { ReferenceDem dem(feet); }).find("vertical unit 9999"), std::string::npos);
}

// Item 7, horizontal units: a DEM in a US-feet state plane (EPSG:2263, NAD83 / New York Long Island (ftUS),
// pixel scale 100 ftUS) is sampled where PROJ puts each point in feet (already right: PROJ's transformation is
// in the CRS's unit), and its posting is in metres (30.48 m; it was given as 100).
TEST(ReferenceDemKeys, FeetStatePlane) {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* raw = proj_create_crs_to_crs(ctx, "EPSG:4326", "EPSG:2263", nullptr);
  PJ* pj = proj_normalize_for_visualization(ctx, raw);
  const auto feet = [&](double lon, double lat, double& x, double& y) {
    const PJ_COORD q = proj_trans(pj, PJ_FWD, proj_coord(lon, lat, 0, 0));
    x = q.xy.x;
    y = q.xy.y;
  };
  double xc, yc;
  feet(-73.9, 40.75, xc, yc);
  const double x0 = std::floor(xc) - 20000, y0 = std::floor(yc) + 20000;
  const auto z = [&](double x, double y) { return 10 + 0.001 * (x - x0) + 0.002 * (y0 - y); };
  DemRaster r;
  r.epsg = 2263;
  r.x0 = x0;
  r.y0 = y0;
  r.dx = r.dy = 100;
  r.width = r.height = 400;
  for (long j = 0; j < r.height; ++j)
    for (long i = 0; i < r.width; ++i) r.data.push_back(static_cast<float>(z(x0 + 100 * i, y0 - 100 * j)));
  const std::string path = scratch("ftus.tif");
  write_reference_dem(path, r);
  ReferenceDem dem(path);
  EXPECT_NEAR(dem.posting_m(), 30.48006, 1e-4);
  for (const double lon : {-73.92, -73.9, -73.88}) {
    double x, y;
    feet(lon, 40.76, x, y);
    EXPECT_NEAR(height_at(dem, lon, 40.76), z(x, y), 1e-3) << lon;
  }
  proj_destroy(pj);
  proj_destroy(raw);
  proj_context_destroy(ctx);
}

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

// Item 5: a DEM of one deflated strip of 12000 x 12000 float32 cells (576 MB decoded, a file of a few hundred
// kB) is sampled, out of row order, within 768 MiB of address space: the strip is read by rows, not whole
// (whole it took twice its size). Under the sanitizers (no address-space limit) the same reads run unlimited.
TEST(ReferenceDemBlocks, HugeStripReadByRows) {
  const std::string path = scratch("one_strip.tif");
  write_one_block_dem(path, 12000, false);
  const auto sample = [&path]() {
    ReferenceDem dem(path);
    bool ok = true;
    for (const double row : {11000.25, 20.5, 6000.75, 11998.5, 3.0}) {
      double h = NAN;
      ok = ok && dem.height(5 + 0.1, 44 - row * 1e-4, h) && std::fabs(h - row) < 1e-3;
    }
    return ok;
  };
  if (tpkit_test::kSanitized) {
    EXPECT_TRUE(sample());
  } else {
    EXPECT_EQ(tpkit_test::run_limited(rlim_t(768) << 20, sample), 0);
  }
}

// Item 5: a tile above kMaxDemBlockBytes (4608 x 4608 float32 cells, 81 MiB) is refused when the DEM is
// opened, with the bound and the way out, rather than decoded whole at the first sample.
TEST(ReferenceDemBlocks, HugeTileRefused) {
  const std::string path = scratch("one_tile.tif");
  write_one_block_dem(path, 4608, true);
  const std::string e = refusal([&] { ReferenceDem dem(path); });
  EXPECT_NE(e.find(path + ": tiles of 4608x4608 cells (81 MiB decoded) exceed the 64 MiB a DEM block may take"),
            std::string::npos)
      << e;
}
