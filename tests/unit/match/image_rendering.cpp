// The grey rendering tp-match reads of a multi-band image (issue 51): an RGB image's luminance, a
// multispectral image's mean of the bands, one band when asked; computed region by region in the
// file's radiometry, named in the detector line (which keys the keypoint cache).
#include <gtest/gtest.h>
#include <tiffio.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "tpkit/core/error.hpp"
#include "tpkit/match/image_tiles.hpp"
#include "tpkit/match/sift_tiles.hpp"

using namespace tpkit;

namespace {

// Sample (x, y) of band k: different patterns in every band, 8-bit.
uint8_t sample(long x, long y, int k) { return static_cast<uint8_t>((x * (3 + k) + y * (7 - 2 * k) + 40 * k) % 256); }

// A W x H 8-bit image of `bands` pixel-interleaved bands in strips of 5 rows, its photometric
// interpretation as given (RGB or MINISBLACK).
void write_bands(const std::string& path, long W, long H, int bands, uint16_t photometric) {
  TIFF* tif = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(tif, nullptr);
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(W));
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(H));
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, static_cast<uint16_t>(bands));
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 8);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, photometric);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 5);
  if (bands > 3) {
    std::vector<uint16_t> extra(static_cast<size_t>(bands - (photometric == PHOTOMETRIC_RGB ? 3 : 1)), EXTRASAMPLE_UNSPECIFIED);
    TIFFSetField(tif, TIFFTAG_EXTRASAMPLES, static_cast<uint16_t>(extra.size()), extra.data());
  }
  std::vector<uint8_t> row(static_cast<size_t>(W * bands));
  for (long y = 0; y < H; ++y) {
    for (long x = 0; x < W; ++x)
      for (int k = 0; k < bands; ++k) row[static_cast<size_t>(x * bands + k)] = sample(x, y, k);
    ASSERT_EQ(TIFFWriteScanline(tif, row.data(), static_cast<uint32_t>(y), 0), 1);
  }
  TIFFClose(tif);
}

struct Dir {
  std::filesystem::path p = std::filesystem::temp_directory_path() / ("tpkit_rendering_" + std::to_string(::getpid()));
  Dir() { std::filesystem::create_directories(p); }
  ~Dir() { std::filesystem::remove_all(p); }
  std::string operator/(const std::string& f) const { return (p / f).string(); }
};

}  // namespace

// An RGB file is read as its luminance 0.299 R + 0.587 G + 0.114 B (its own radiometry, not rounded),
// region by region, and the detector line says so; --band still reads one band, named as before.
TEST(ImageRendering, RgbIsReadAsLuminance) {
  Dir d;
  const std::string path = d / "rgb.tif";
  write_bands(path, 60, 40, 3, PHOTOMETRIC_RGB);
  const ImageSource s = open_image_source(path, std::nullopt, std::nullopt, "");
  EXPECT_TRUE(s.info.rgb);
  EXPECT_EQ(s.rendering, "luminance=0.299R+0.587G+0.114B");
  const Raster r = read_valid_region(s, 7, 11, 30, 17);
  ASSERT_EQ(r.width, 30);
  ASSERT_EQ(r.height, 17);
  for (long y = 0; y < r.height; ++y)
    for (long x = 0; x < r.width; ++x) {
      const long X = r.x0 + x, Y = r.y0 + y;
      ASSERT_NEAR(r.at(x, y), 0.299 * sample(X, Y, 0) + 0.587 * sample(X, Y, 1) + 0.114 * sample(X, Y, 2), 1e-4) << X << " " << Y;
    }
  const std::string tag = detector_tag(SiftOptions{}, s);
  EXPECT_NE(tag.find(" luminance=0.299R+0.587G+0.114B "), std::string::npos) << tag;

  const ImageSource g = open_image_source(path, 1, std::nullopt, "");  // --band 2
  EXPECT_EQ(g.rendering, "band=2");
  const Raster rg = read_valid_region(g, 0, 0, 60, 40);
  for (long y = 0; y < 40; ++y)
    for (long x = 0; x < 60; ++x) ASSERT_EQ(rg.at(x, y), static_cast<float>(sample(x, y, 1)));
  // the keypoint cache and pair geometry key on the detector line: band 1 is not the luminance
  EXPECT_NE(detector_tag(SiftOptions{}, open_image_source(path, 0, std::nullopt, "")), tag);
  EXPECT_THROW(open_image_source(path, 3, std::nullopt, ""), InputError);  // no band 4
}

// A multispectral file (not RGB) is read as the mean of its bands; a pixel that is nodata in any band
// is invalid; a single-band file is read unchanged, named band 1 as before.
TEST(ImageRendering, MultispectralIsReadAsTheMeanOfItsBands) {
  Dir d;
  const std::string path = d / "ms.tif";
  write_bands(path, 50, 30, 4, PHOTOMETRIC_MINISBLACK);
  const ImageSource s = open_image_source(path, std::nullopt, std::nullopt, "");
  EXPECT_FALSE(s.info.rgb);
  EXPECT_EQ(s.rendering, "mean=bands1-4");
  const Raster r = read_valid_region(s, 0, 0, 50, 30);
  for (long y = 0; y < 30; ++y)
    for (long x = 0; x < 50; ++x)
      ASSERT_NEAR(r.at(x, y), (sample(x, y, 0) + sample(x, y, 1) + sample(x, y, 2) + sample(x, y, 3)) / 4.0, 1e-4);

  // nodata: the value of sample(x, y, 2) at (10, 3), which no other band has there
  const double nd = sample(10, 3, 2);
  const ImageSource n = open_image_source(path, std::nullopt, nd, "");
  const Raster rn = read_valid_region(n, 0, 0, 50, 30);
  EXPECT_TRUE(std::isnan(rn.at(10, 3)));
  long invalid = 0;
  for (long y = 0; y < 30; ++y)
    for (long x = 0; x < 50; ++x) {
      bool any = false;
      for (int k = 0; k < 4; ++k) any = any || sample(x, y, k) == nd;
      EXPECT_EQ(std::isnan(rn.at(x, y)), any) << x << " " << y;
      invalid += any;
    }
  EXPECT_GT(invalid, 0);

  const std::string grey = d / "grey.tif";
  write_bands(grey, 20, 10, 1, PHOTOMETRIC_MINISBLACK);
  const ImageSource g = open_image_source(grey, std::nullopt, std::nullopt, "");
  EXPECT_EQ(g.rendering, "band=1");
  EXPECT_EQ(detector_tag(SiftOptions{}, g), detector_tag(SiftOptions{}, open_image_source(grey, 0, std::nullopt, "")));
  const Raster rg = read_valid_region(g, 0, 0, 20, 10);
  for (long y = 0; y < 10; ++y)
    for (long x = 0; x < 20; ++x) ASSERT_EQ(rg.at(x, y), static_cast<float>(sample(x, y, 0)));
}
