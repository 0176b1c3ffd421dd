// The libtiff reader against the values written and against OpenImageIO's reading of the same files, over
// the layouts satellite products come in: strips and tiles, compressed or not, bands interleaved or in
// planes, integer and float samples, either byte order; and the writer's files read back by both.
#include <gtest/gtest.h>
#include <tiffio.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/oiio_images.hpp"
#include "tpkit/core/tiff_image.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {
fs::path scratch(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("tpkit-tiff-test-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d / name;
}

struct Layout {
  std::string name;
  int bits;
  int format;  // SAMPLEFORMAT_*
  int bands;
  bool planar, tiled, big_endian;
  int compression;
};

// The value of band b at (x, y): distinct per pixel and band, representable in every sample type.
double value(const Layout& L, long x, long y, int b) {
  double v = (x * 3 + y * 7 + b * 50) % 251;
  if (L.format == SAMPLEFORMAT_INT) v -= 100;
  if (L.format == SAMPLEFORMAT_IEEEFP) v = v * 0.25 - 3;
  return v;
}

template <class T>
void put(std::vector<unsigned char>& buf, size_t i, double v) {
  T t = static_cast<T>(v);
  std::memcpy(buf.data() + i * sizeof(T), &t, sizeof(T));
}
void put_sample(const Layout& L, std::vector<unsigned char>& buf, size_t i, double v) {
  if (L.format == SAMPLEFORMAT_IEEEFP) return L.bits == 32 ? put<float>(buf, i, v) : put<double>(buf, i, v);
  const bool s = L.format == SAMPLEFORMAT_INT;
  if (L.bits == 8) return s ? put<int8_t>(buf, i, v) : put<uint8_t>(buf, i, v);
  if (L.bits == 16) return s ? put<int16_t>(buf, i, v) : put<uint16_t>(buf, i, v);
  return s ? put<int32_t>(buf, i, v) : put<uint32_t>(buf, i, v);
}

// Writes a W x H image of layout L with libtiff (tiles 32 x 16, strips of 7 rows).
void write_layout(const std::string& path, const Layout& L, long W, long H) {
  TIFF* tif = TIFFOpen(path.c_str(), L.big_endian ? "wb" : "wl");
  ASSERT_NE(tif, nullptr);
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(W));
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(H));
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, L.bands);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, L.bits);
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, L.format);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, L.bands == 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, L.planar ? PLANARCONFIG_SEPARATE : PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, L.compression);
  const size_t bps = L.bits / 8, per_pixel = L.planar ? 1 : L.bands;
  const int planes = L.planar ? L.bands : 1;
  if (L.tiled) {
    const long tw = 32, th = 16;
    TIFFSetField(tif, TIFFTAG_TILEWIDTH, static_cast<uint32_t>(tw));
    TIFFSetField(tif, TIFFTAG_TILELENGTH, static_cast<uint32_t>(th));
    std::vector<unsigned char> buf(tw * th * per_pixel * bps);
    for (int p = 0; p < planes; ++p)
      for (long ty = 0; ty < H; ty += th)
        for (long tx = 0; tx < W; tx += tw) {
          std::fill(buf.begin(), buf.end(), 0);
          for (long y = 0; y < th; ++y)
            for (long x = 0; x < tw; ++x)
              for (size_t k = 0; k < per_pixel; ++k) {
                const int b = L.planar ? p : static_cast<int>(k);
                if (tx + x < W && ty + y < H) put_sample(L, buf, (y * tw + x) * per_pixel + k, value(L, tx + x, ty + y, b));
              }
          ASSERT_GE(TIFFWriteTile(tif, buf.data(), static_cast<uint32_t>(tx), static_cast<uint32_t>(ty), 0, static_cast<uint16_t>(p)), 0);
        }
  } else {
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 7);
    std::vector<unsigned char> row(W * per_pixel * bps);
    for (int p = 0; p < planes; ++p)
      for (long y = 0; y < H; ++y) {
        for (long x = 0; x < W; ++x)
          for (size_t k = 0; k < per_pixel; ++k) put_sample(L, row, x * per_pixel + k, value(L, x, y, L.planar ? p : static_cast<int>(k)));
        ASSERT_EQ(TIFFWriteScanline(tif, row.data(), static_cast<uint32_t>(y), static_cast<uint16_t>(p)), 1);
      }
  }
  TIFFClose(tif);
}
}  // namespace

TEST(TiffImage, EveryLayoutReadsItsValuesAndAgreesWithOpenImageIO) {
  const std::vector<Layout> layouts = {
      {"u16-strips", 16, SAMPLEFORMAT_UINT, 1, false, false, false, COMPRESSION_NONE},
      {"u16-strips-deflate-be", 16, SAMPLEFORMAT_UINT, 1, false, false, true, COMPRESSION_ADOBE_DEFLATE},
      {"u8-rgb-contig-lzw", 8, SAMPLEFORMAT_UINT, 3, false, false, false, COMPRESSION_LZW},
      {"i16-rgb-planar-strips", 16, SAMPLEFORMAT_INT, 3, true, false, true, COMPRESSION_NONE},
      {"f32-tiles-deflate", 32, SAMPLEFORMAT_IEEEFP, 1, false, true, false, COMPRESSION_ADOBE_DEFLATE},
      {"u16-rgb-tiles-contig-be", 16, SAMPLEFORMAT_UINT, 3, false, true, true, COMPRESSION_NONE},
      {"f64-2band-planar-tiles", 64, SAMPLEFORMAT_IEEEFP, 2, true, true, false, COMPRESSION_ADOBE_DEFLATE},
      {"u32-strips", 32, SAMPLEFORMAT_UINT, 1, false, false, true, COMPRESSION_NONE},
      {"u8-rgb-contig-strips", 8, SAMPLEFORMAT_UINT, 3, false, false, false, COMPRESSION_NONE},
  };
  const long W = 75, H = 41;
  for (const Layout& L : layouts) {
    SCOPED_TRACE(L.name);
    const std::string p = scratch(L.name + ".tif").string();
    write_layout(p, L, W, H);
    ASSERT_TRUE(is_tiff_file(p));
    auto info = tiff_image_info(p);
    ASSERT_TRUE(info.has_value());
    EXPECT_EQ(info->width, W);
    EXPECT_EQ(info->height, H);
    EXPECT_EQ(info->bands, L.bands);
    EXPECT_EQ(info->bits, L.bits);
    EXPECT_EQ(info->rgb, L.bands == 3);  // photometric RGB as write_layout writes it; 2 bands MINISBLACK
    const ImageInfo oi = oiio_image_info(p);
    EXPECT_EQ(oi.rgb, L.bands == 3);
    EXPECT_EQ(oi.width, W);
    EXPECT_EQ(oi.bands, L.bands);
    EXPECT_EQ(info->format, oi.format);
    for (int b = 0; b < L.bands; ++b) {
      // a window across chunk edges, clipped at the right and bottom borders
      auto r = read_tiff_region(p, b, 29, 13, 60, 40);
      ASSERT_TRUE(r.has_value());
      ASSERT_EQ(r->width, W - 29);
      ASSERT_EQ(r->height, H - 13);
      const Raster o = oiio_read_region(p, b, 29, 13, 60, 40);
      ASSERT_EQ(o.data.size(), r->data.size());
      for (long y = 0; y < r->height; ++y)
        for (long x = 0; x < r->width; ++x) {
          ASSERT_EQ(r->at(x, y), static_cast<float>(value(L, 29 + x, 13 + y, b))) << "band " << b << " at " << x << "," << y;
          ASSERT_EQ(o.at(x, y), r->at(x, y));
        }
      // read into the memory of a raster done with (NaN-filled, larger or smaller than the region): the
      // same raster, every sample written
      for (size_t held : {r->data.size() + 500, r->data.size() / 3}) {
        Raster reuse;
        reuse.x0 = 7, reuse.width = 3;
        reuse.data.assign(held, std::numeric_limits<float>::quiet_NaN());
        auto q = read_tiff_region(p, b, 29, 13, 60, 40, std::move(reuse));
        ASSERT_TRUE(q.has_value());
        EXPECT_EQ(q->x0, r->x0);
        EXPECT_EQ(q->y0, r->y0);
        EXPECT_EQ(q->width, r->width);
        EXPECT_EQ(q->height, r->height);
        ASSERT_EQ(q->data.size(), r->data.size());
        for (size_t i = 0; i < r->data.size(); ++i) ASSERT_EQ(q->data[i], r->data[i]) << "sample " << i << ", reused " << held;
      }
    }
    // several bands at once (tp-match's luminance), in any order, one of them twice: each as read alone
    std::vector<int> bands;
    for (int b = L.bands - 1; b >= 0; --b) bands.push_back(b);
    bands.push_back(L.bands - 1);
    const auto m = read_tiff_bands(p, bands, 29, 13, 60, 40);
    ASSERT_TRUE(m.has_value());
    ASSERT_EQ(m->size(), bands.size());
    for (size_t j = 0; j < bands.size(); ++j) {
      const auto r = read_tiff_region(p, bands[j], 29, 13, 60, 40);
      EXPECT_EQ((*m)[j].x0, r->x0);
      EXPECT_EQ((*m)[j].y0, r->y0);
      EXPECT_EQ((*m)[j].width, r->width);
      EXPECT_EQ((*m)[j].height, r->height);
      EXPECT_EQ((*m)[j].data, r->data) << "band " << bands[j];
    }
    try {
      read_tiff_region(p, L.bands, 0, 0, 4, 4);
      FAIL() << "a band past the last";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("band " + std::to_string(L.bands + 1) + " does not exist"), std::string::npos);
    }
  }
}

TEST(TiffImage, WrittenFilesReadTheSameThroughBothReaders) {
  const long W = 130, H = 70;
  std::vector<uint16_t> px(W * H);
  for (long i = 0; i < W * H; ++i) px[i] = static_cast<uint16_t>((i * 37) % 4096);
  const std::string p = scratch("written.tif").string();
  write_image_u16(p, W, H, px);
  const Raster a = read_band(p), b = oiio_read_region(p, 0, 0, 0, W, H);
  ASSERT_EQ(a.data.size(), px.size());
  for (long i = 0; i < W * H; ++i) {
    ASSERT_EQ(a.data[i], px[i]);
    ASSERT_EQ(b.data[i], px[i]);
  }
  // PNG goes through the module, and reads back through it
  const std::string png = scratch("written.png").string();
  std::vector<uint8_t> u8(W * H);
  for (long i = 0; i < W * H; ++i) u8[i] = static_cast<uint8_t>(i % 256);
  write_image_u8(png, W, H, u8);
  EXPECT_FALSE(is_tiff_file(png));
  const ImageInfo pi = image_info(png);
  EXPECT_EQ(pi.format, "uint8");
  const Raster c = read_region(png, 0, 5, 6, 20, 10);
  EXPECT_EQ(c.at(3, 2), static_cast<float>(((6 + 2) * W + 5 + 3) % 256));
}

TEST(TiffImage, TruncatedFileIsAnErrorNotZeros) {
  const long W = 200, H = 100;
  std::vector<uint16_t> px(W * H);
  for (long i = 0; i < W * H; ++i) px[i] = static_cast<uint16_t>((i * 7919) % 65536);  // incompressible
  const std::string p = scratch("cut.tif").string();
  write_image_u16(p, W, H, px);
  const auto size = fs::file_size(p);
  fs::resize_file(p, size / 2);
  EXPECT_THROW(read_band(p), InputError);
}
