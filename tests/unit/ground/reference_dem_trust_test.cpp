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
