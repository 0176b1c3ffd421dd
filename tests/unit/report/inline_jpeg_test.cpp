// Inline pictures: base64 against RFC 4648's test vectors, and a JPEG data URI that decodes (libjpeg) back to
// the picture it was made of, within JPEG's loss.
#include <gtest/gtest.h>
#include <jpeglib.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "tpkit/report/inline_jpeg.hpp"

using namespace tpkit;

namespace {
std::string b64(const std::string& s) { return base64_encode(reinterpret_cast<const uint8_t*>(s.data()), s.size()); }

// base64 back to bytes (the test's own decoder).
std::vector<uint8_t> unbase64(const std::string& s) {
  const std::string t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<uint8_t> out;
  unsigned v = 0;
  int bits = 0;
  for (char c : s) {
    if (c == '=') break;
    v = (v << 6) | static_cast<unsigned>(t.find(c));
    bits += 6;
    if (bits >= 8) out.push_back(static_cast<uint8_t>((v >> (bits -= 8)) & 255));
  }
  return out;
}
}  // namespace

TEST(InlineJpeg, Base64Rfc4648Vectors) {
  EXPECT_EQ(b64(""), "");
  EXPECT_EQ(b64("f"), "Zg==");
  EXPECT_EQ(b64("fo"), "Zm8=");
  EXPECT_EQ(b64("foo"), "Zm9v");
  EXPECT_EQ(b64("foob"), "Zm9vYg==");
  EXPECT_EQ(b64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(b64("foobar"), "Zm9vYmFy");
  const std::string high = "\xff\xfe\x80";
  EXPECT_EQ(b64(high), "//6A");
}

TEST(InlineJpeg, DecodesBackToThePicture) {
  const int w = 40, h = 24;
  std::vector<uint8_t> px(static_cast<size_t>(w * h * 3));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = &px[static_cast<size_t>((y * w + x) * 3)];
      p[0] = static_cast<uint8_t>(x * 6), p[1] = static_cast<uint8_t>(y * 10), p[2] = 128;  // smooth ramps
    }
  const std::string uri = jpeg_data_uri(px, w, h, 3, 95);
  const std::string prefix = "data:image/jpeg;base64,";
  ASSERT_EQ(uri.compare(0, prefix.size(), prefix), 0);
  std::vector<uint8_t> jpg = unbase64(uri.substr(prefix.size()));
  jpeg_decompress_struct d;
  jpeg_error_mgr err;
  d.err = jpeg_std_error(&err);
  jpeg_create_decompress(&d);
  jpeg_mem_src(&d, jpg.data(), jpg.size());
  ASSERT_EQ(jpeg_read_header(&d, TRUE), JPEG_HEADER_OK);
  jpeg_start_decompress(&d);
  ASSERT_EQ(static_cast<int>(d.output_width), w);
  ASSERT_EQ(static_cast<int>(d.output_height), h);
  ASSERT_EQ(d.output_components, 3);
  std::vector<uint8_t> back(px.size());
  while (d.output_scanline < d.output_height) {
    JSAMPROW row = &back[static_cast<size_t>(d.output_scanline) * w * 3];
    jpeg_read_scanlines(&d, &row, 1);
  }
  jpeg_finish_decompress(&d);
  jpeg_destroy_decompress(&d);
  double worst = 0;
  for (size_t i = 0; i < px.size(); ++i) worst = std::max(worst, std::fabs(double(px[i]) - double(back[i])));
  EXPECT_LE(worst, 8) << "JPEG at quality 95 of smooth ramps";
}

TEST(InlineJpeg, SizeThatDoesNotAgreeRefused) {
  EXPECT_THROW(jpeg_data_uri(std::vector<uint8_t>(10), 4, 4, 3, 90), std::invalid_argument);
  EXPECT_THROW(jpeg_data_uri(std::vector<uint8_t>(16), 4, 4, 2, 90), std::invalid_argument);
}
