// Image reading by region, 16-bit writing, and the RPC tag of the real Pléiades crops.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {
fs::path scratch(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("tpkit-image-test-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d / name;
}
const std::string kData = std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille";
}  // namespace

TEST(ImageIo, WriteStripsThenReadRegions) {
  const long W = 300, H = 170;
  auto p = scratch("ramp.tif").string();
  {
    TiffWriterU16 w(p, W, H);
    std::vector<uint16_t> strip(W * 50);
    for (long y0 = 0; y0 < H; y0 += 50) {
      long rows = std::min(50L, H - y0);
      for (long y = 0; y < rows; ++y)
        for (long x = 0; x < W; ++x) strip[y * W + x] = static_cast<uint16_t>(x + 7 * (y0 + y));
      w.write_rows(y0, rows, strip.data());
    }
    w.close();
  }
  auto info = image_info(p);
  EXPECT_EQ(info.width, W);
  EXPECT_EQ(info.height, H);
  EXPECT_EQ(info.bands, 1);
  EXPECT_EQ(info.format, "uint16");
  auto r = read_region(p, 0, 250, 160, 100, 100);  // clipped at the border
  EXPECT_EQ(r.x0, 250);
  EXPECT_EQ(r.width, 50);
  EXPECT_EQ(r.height, 10);
  EXPECT_EQ(r.at(3, 4), 253 + 7 * 164);
  try {
    read_region(p, 1, 0, 0, 10, 10);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("band 2 does not exist (the image has 1)"), std::string::npos);
  }
}

TEST(ImageIo, NotAnImage) {
  auto p = scratch("text.tif").string();
  { std::ofstream(p) << "hello, not a tiff\n"; }
  EXPECT_THROW(image_info(p), InputError);
  EXPECT_THROW(image_info(scratch("missing.tif").string()), InputError);
  EXPECT_THROW(read_rpc_tag(p), InputError);
}

TEST(ImageIo, PleiadesRpcTagHas92Values) {
  if (!fs::exists(kData + "/img_01.tif")) GTEST_SKIP() << "no " << kData;
  auto v = read_rpc_tag(kData + "/img_01.tif");
  ASSERT_TRUE(v.has_value());
  EXPECT_GT((*v)[7], 0);   // LINE_SCALE
  EXPECT_NEAR((*v)[4], 43.26, 0.5);  // LAT_OFF
}

TEST(ImageIo, GeoTiffGridRoundTripsAndNeedsGeoreferencing) {
  GeoGrid g;
  g.width = 5;
  g.height = 3;
  g.lon0 = 5.4;
  g.lat0 = 43.3;
  g.dlon = 1.25e-5;
  g.dlat = 1e-5;
  for (int i = 0; i < 15; ++i) g.data.push_back(100.0f + 0.5f * i);
  auto p = scratch("dem.tif").string();
  write_geotiff_grid(p, g);
  GeoGrid r = read_geotiff_grid(p);
  EXPECT_EQ(r.width, 5);
  EXPECT_EQ(r.height, 3);
  EXPECT_EQ(r.lon0, g.lon0);  // PixelIsPoint: the tie point is the first sample
  EXPECT_EQ(r.lat0, g.lat0);
  EXPECT_EQ(r.dlon, g.dlon);
  EXPECT_EQ(r.dlat, g.dlat);
  EXPECT_EQ(r.data, g.data);
  EXPECT_FALSE(read_rpc_tag(p).has_value());
  auto plain = scratch("plain.tif").string();
  write_image_u16(plain, 4, 4, std::vector<uint16_t>(16, 7));
  try {
    read_geotiff_grid(plain);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no GeoTIFF georeferencing"), std::string::npos);
  }
}
