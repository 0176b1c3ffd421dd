// Image reading by region, 16-bit writing, and the RPC tag of the real Pléiades crops.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "tpkit/error.hpp"
#include "tpkit/image_io.hpp"

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
  EXPECT_THROW(read_rpc(p), InputError);
}

TEST(ImageIo, PleiadesRpcProjectsIntoTheCrop) {
  if (!fs::exists(kData + "/img_01.tif")) GTEST_SKIP() << "no " << kData;
  auto info = image_info(kData + "/img_01.tif");
  EXPECT_EQ(info.format, "uint16");
  auto rpc = read_rpc(kData + "/img_01.tif");
  ASSERT_TRUE(rpc.has_value());
  // the centre of crop 1 at the reference height is seen inside crops 2 and 3 too (the triplet overlaps)
  auto ll = rpc->localize(info.width / 2.0, info.height / 2.0, rpc->height_off);
  auto back = rpc->project(ll[0], ll[1], rpc->height_off);
  EXPECT_NEAR(back[0], info.width / 2.0, 1e-6);
  EXPECT_NEAR(back[1], info.height / 2.0, 1e-6);
  EXPECT_NEAR(ll[1], 43.26, 0.05);
  EXPECT_NEAR(ll[0], 5.44, 0.1);
  for (int i = 2; i <= 3; ++i) {
    auto r = read_rpc(kData + "/img_0" + std::to_string(i) + ".tif");
    ASSERT_TRUE(r.has_value());
    auto q = r->project(ll[0], ll[1], rpc->height_off);
    EXPECT_GT(q[0], 0);
    EXPECT_LT(q[0], info.width);
    EXPECT_GT(q[1], 0);
    EXPECT_LT(q[1], info.height);
  }
}
