// Image reading by region, 16-bit writing, and the RPC tag of the real Pléiades crops.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
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

TEST(ImageIo, CropOfTheWholeBandIsTheRegionRead) {
  const long W = 300, H = 170;
  auto p = scratch("ramp-crop.tif").string();
  {
    TiffWriterU16 w(p, W, H);
    std::vector<uint16_t> rows(W * H);
    for (long y = 0; y < H; ++y)
      for (long x = 0; x < W; ++x) rows[y * W + x] = static_cast<uint16_t>(3 * x + 11 * y);
    w.write_rows(0, H, rows.data());
    w.close();
  }
  const Raster whole = read_band(p, 0);
  // inside, over each border, over a corner, around the whole image, and outside it
  const long regions[][4] = {{40, 30, 64, 20}, {-5, 10, 30, 30}, {280, 150, 40, 40}, {-3, -4, 400, 300}, {310, 10, 5, 5}, {0, 169, 300, 1}};
  for (const auto& q : regions) {
    const Raster a = crop_region(whole, q[0], q[1], q[2], q[3]), b = read_region(p, 0, q[0], q[1], q[2], q[3]);
    EXPECT_EQ(a.x0, b.x0);
    EXPECT_EQ(a.y0, b.y0);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.data, b.data) << "region " << q[0] << " " << q[1] << " " << q[2] << " " << q[3];
  }
  // a crop of a crop is the crop: positions stay in full-image pixels
  const Raster part = crop_region(whole, 100, 50, 120, 80), sub = crop_region(part, 90, 40, 50, 30);
  EXPECT_EQ(sub.x0, 100);
  EXPECT_EQ(sub.y0, 50);
  EXPECT_EQ(sub.width, 40);
  EXPECT_EQ(sub.height, 20);
  EXPECT_EQ(sub.at(5, 7), 3 * 105 + 11 * 57);
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

namespace {
// A little-endian GeoTIFF written byte by byte whose header declares W x H float32 samples in one
// uncompressed strip of W x H x 4 bytes, while the file holds 16 bytes of them (issue 23: 550 bytes
// declaring 25 000 x 25 000 made the reader allocate 2.5 GB).
void write_lying_dem(const std::string& path, uint32_t w, uint32_t h) {
  std::string b = "II*";
  b += '\0';
  auto u16 = [&](uint16_t v) { b += static_cast<char>(v & 0xff), b += static_cast<char>(v >> 8); };
  auto u32 = [&](uint32_t v) { for (int k = 0; k < 4; ++k) b += static_cast<char>((v >> (8 * k)) & 0xff); };
  auto f64 = [&](double v) {
    uint64_t u;
    std::memcpy(&u, &v, 8);
    for (int k = 0; k < 8; ++k) b += static_cast<char>((u >> (8 * k)) & 0xff);
  };
  const uint32_t n = 13, data = 8 + 2 + 12 * n + 4;  // scale at data, tie at +24, keys at +72, strip at +96
  u32(8);
  u16(n);
  auto entry = [&](uint16_t tag, uint16_t type, uint32_t count, uint32_t value) { u16(tag), u16(type), u32(count), u32(value); };
  entry(256, 4, 1, w);
  entry(257, 4, 1, h);
  entry(258, 3, 1, 32);
  entry(259, 3, 1, 1);
  entry(262, 3, 1, 1);
  entry(273, 4, 1, data + 96);
  entry(277, 3, 1, 1);
  entry(278, 4, 1, h);
  entry(279, 4, 1, static_cast<uint32_t>(std::min<uint64_t>(0xffffffffu, uint64_t(w) * h * 4)));
  entry(339, 3, 1, 3);
  entry(33550, 12, 3, data);
  entry(33922, 12, 6, data + 24);
  entry(34735, 3, 12, data + 72);
  u32(0);
  for (double v : {1e-4, 1e-4, 0.0}) f64(v);
  for (double v : {0.0, 0.0, 0.0, 5.0, 43.5, 0.0}) f64(v);
  for (uint16_t v : {1, 1, 0, 2, 1024, 0, 1, 2, 2048, 0, 1, 4326}) u16(v);
  for (int k = 0; k < 4; ++k) f64(0), b.resize(b.size() - 4);  // 16 bytes of samples
  std::ofstream(path, std::ios::binary) << b;
}
}  // namespace

TEST(ImageIo, DemHeaderDeclaringMoreThanTheFileIsRefusedWithoutAllocatingIt) {
  const auto p = scratch("lying.tif").string();
  write_lying_dem(p, 25000, 25000);
  ASSERT_LT(fs::file_size(p), 600u);
  // a scene's window in the middle of the declared grid: its rows lie beyond the 16 bytes held
  const GeoBounds scene{5.1, 5.11, 43.0, 43.01};
  try {
    read_geotiff_grid(p, &scene);
    FAIL() << "a DEM holding 16 bytes of a declared 2.5 GB was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("beyond the end of the file"), std::string::npos) << e.what();
  }
  // the whole declared grid is more samples than any window is allowed
  try {
    read_geotiff_grid(p);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("larger than 400000000 samples"), std::string::npos) << e.what();
  }
  // a small declared grid whose strip fits the file reads, byte for byte (4 x 1 samples of 0)
  write_lying_dem(p, 4, 1);
  const GeoGrid g = read_geotiff_grid(p);
  EXPECT_EQ(g.width, 4);
  EXPECT_EQ(g.data, std::vector<float>(4, 0.0f));
}
