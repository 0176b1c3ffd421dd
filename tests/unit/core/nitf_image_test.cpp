// NITF 2.1 reading and writing: the WorldView-3 crops of ../shared/data/nitf-wv3 against GDAL's reading
// of them (statistics computed once with GDAL 3.6 `gdalinfo -stats`), every block layout the reader
// takes on files assembled here byte by byte (band interleaves, pad pixels, block masks, justification,
// sample types), the writer read back, and malformed files refused with what is wrong.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/nitf_image.hpp"

using namespace tpkit;

namespace {

const std::string kWv3 = std::string(TPKIT_SHARED_DIR) + "/data/nitf-wv3/";

std::string field(const std::string& s, size_t n) {
  std::string o = s.substr(0, n);
  o.resize(n, ' ');
  return o;
}
std::string num(uint64_t v, size_t n) {
  std::string s = std::to_string(v);
  return std::string(n - s.size(), '0') + s;
}

// A NITF 2.1 file with one image segment laid out as asked, assembled field by field (MIL-STD-2500C).
struct Layout {
  long rows = 29, cols = 37;
  int bands = 1, nbpp = 16, abpp = 16;
  std::string pvtype = "INT", ic = "NC", version = "NITF02.10", irep = "MONO";
  char imode = 'B', pjust = 'R';
  long nppbh = 16, nppbv = 12;
  int image_segments = 1;
};

long nbpr(const Layout& l) { return (l.cols + l.nppbh - 1) / l.nppbh; }
long nbpc(const Layout& l) { return (l.rows + l.nppbv - 1) / l.nppbv; }

std::string nitf_bytes(const Layout& l, const std::string& data, const std::string& tres = "") {
  std::string sub = "IM" + field("t", 10) + "20261203000000" + field("", 17) + field("", 80) + "U" + field("", 166) + "0" + field("", 42);
  sub += num(l.rows, 8) + num(l.cols, 8) + field(l.pvtype, 3) + field(l.irep, 8) + field("VIS", 8) + num(l.abpp, 2) + l.pjust;
  sub += " 0" + l.ic + (l.ic == "NC" || l.ic == "NM" ? "" : "N010") + num(l.bands, 1);
  for (int b = 0; b < l.bands; ++b) sub += field("M", 2) + field("", 6) + "N" + field("", 3) + "0";
  sub += "0" + std::string(1, l.imode) + num(nbpr(l), 4) + num(nbpc(l), 4) + num(l.nppbh, 4) + num(l.nppbv, 4) + num(l.nbpp, 2);
  sub += "001000" "0000000000" "1.0 " "00000";
  sub += tres.empty() ? std::string("00000") : num(tres.size() + 3, 5) + "000" + tres;
  std::string segs;
  for (int i = 0; i < l.image_segments; ++i) segs += num(sub.size(), 6) + num(data.size(), 10);
  const size_t hl = 360 + 3 + segs.size() + 25;
  std::string fh = l.version + "03BF01" + field("t", 10) + "20261203000000" + field("", 80) + "U" + field("", 166) + "00000000000" +
                   std::string(3, '\0') + field("", 42);
  std::string body;
  for (int i = 0; i < l.image_segments; ++i) body += sub + data;
  fh += num(hl + body.size(), 12) + num(hl, 6) + num(l.image_segments, 3) + segs + "000000000000000" "00000" "00000";
  EXPECT_EQ(fh.size(), hl);
  return fh + body;
}

// The samples of the layout in file order (big-endian), pad pixels 0; value(b, x, y) as the raw integer
// (already justified) or the real value.
using Value = std::function<double(int, long, long)>;
std::string put_sample(const Layout& l, double v) {
  std::string s(l.nbpp / 8, '\0');
  uint64_t u;
  if (l.pvtype == "R") {
    float f = static_cast<float>(v);
    uint32_t w;
    std::memcpy(&w, &f, 4);
    u = w;
  } else {
    u = static_cast<uint64_t>(static_cast<int64_t>(v));
  }
  for (int i = 0; i < l.nbpp / 8; ++i) s[i] = static_cast<char>((u >> (8 * (l.nbpp / 8 - 1 - i))) & 0xFF);
  return s;
}
// One block's bytes (all bands for B/P/R, band `only` for S).
std::string block_bytes(const Layout& l, long br, long bc, const Value& value, int only = -1) {
  std::string out;
  auto at = [&](int b, long x, long y) {
    const long gx = bc * l.nppbh + x, gy = br * l.nppbv + y;
    return put_sample(l, gx < l.cols && gy < l.rows ? value(b, gx, gy) : 0.0);
  };
  if (l.imode == 'S') {
    for (long y = 0; y < l.nppbv; ++y)
      for (long x = 0; x < l.nppbh; ++x) out += at(only, x, y);
  } else if (l.imode == 'B') {
    for (int b = 0; b < l.bands; ++b)
      for (long y = 0; y < l.nppbv; ++y)
        for (long x = 0; x < l.nppbh; ++x) out += at(b, x, y);
  } else if (l.imode == 'P') {
    for (long y = 0; y < l.nppbv; ++y)
      for (long x = 0; x < l.nppbh; ++x)
        for (int b = 0; b < l.bands; ++b) out += at(b, x, y);
  } else {  // R
    for (long y = 0; y < l.nppbv; ++y)
      for (int b = 0; b < l.bands; ++b)
        for (long x = 0; x < l.nppbh; ++x) out += at(b, x, y);
  }
  return out;
}
std::string image_data(const Layout& l, const Value& value) {
  std::string d;
  const int passes = l.imode == 'S' ? l.bands : 1;
  for (int b = 0; b < passes; ++b)
    for (long br = 0; br < nbpc(l); ++br)
      for (long bc = 0; bc < nbpr(l); ++bc) d += block_bytes(l, br, bc, value, b);
  return d;
}

std::string write_temp(const std::string& name, const std::string& bytes) {
  const std::string path = testing::TempDir() + name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

double pattern(int b, long x, long y) { return static_cast<double>((b * 977 + x * 31 + y * 57) % 2000); }

void expect_region(const std::string& path, const Layout& l, const Value& value, int band, long x0, long y0, long w, long h) {
  const Raster r = read_region(path, band, x0, y0, w, h);
  ASSERT_EQ(r.width, std::min(l.cols, x0 + w) - std::max(0L, x0));
  for (long y = 0; y < r.height; ++y)
    for (long x = 0; x < r.width; ++x)
      ASSERT_EQ(r.at(x, y), static_cast<float>(value(band, r.x0 + x, r.y0 + y))) << path << " band " << band << " at " << r.x0 + x << ", " << r.y0 + y;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(NitfImage, Wv3CropsReadAsGdalReadsThem) {
  // gdalinfo -stats (GDAL 3.6.2): 500 x 500 UInt16, min 188, max 2047, mean 588.292888 (wv3_20)
  const ImageInfo info = image_info(kWv3 + "wv3_20.NTF");
  EXPECT_EQ(info.width, 500);
  EXPECT_EQ(info.height, 500);
  EXPECT_EQ(info.bands, 1);
  EXPECT_EQ(info.format, "uint16");
  EXPECT_EQ(info.bits, 16);
  const Raster r = read_band(kWv3 + "wv3_20.NTF");
  double sum = 0, lo = 1e9, hi = -1e9;
  for (float v : r.data) {
    sum += v;
    lo = std::min<double>(lo, v);
    hi = std::max<double>(hi, v);
  }
  EXPECT_EQ(lo, 188);
  EXPECT_EQ(hi, 2047);
  EXPECT_NEAR(sum / r.data.size(), 588.292888, 5e-7);
  // a region is the same pixels as the whole band
  const Raster part = read_region(kWv3 + "wv3_20.NTF", 0, 123, 456, 77, 100);
  EXPECT_EQ(part.height, 44);
  for (long y = 0; y < part.height; ++y)
    for (long x = 0; x < part.width; ++x) ASSERT_EQ(part.at(x, y), r.at(123 + x, 456 + y));
  const NitfImage im = read_nitf_image(kWv3 + "wv3_20.NTF");
  ASSERT_NE(find_nitf_tre(im, "RPC00B"), nullptr);
  EXPECT_EQ(find_nitf_tre(im, "RPC00B")->data.size(), 1041u);
}

TEST(NitfImage, EveryInterleaveAndPadding) {
  for (char mode : {'B', 'P', 'R', 'S'})
    for (int nbpp : {8, 16, 32}) {
      Layout l;
      l.imode = mode;
      l.bands = 3;
      l.nbpp = l.abpp = nbpp;
      Value v = [nbpp](int b, long x, long y) { return std::fmod(pattern(b, x, y), nbpp == 8 ? 256.0 : 2000.0); };
      const std::string path = write_temp(std::string("il_") + mode + std::to_string(nbpp) + ".ntf", nitf_bytes(l, image_data(l, v)));
      const ImageInfo info = image_info(path);
      EXPECT_EQ(info.bands, 3);
      EXPECT_EQ(info.format, "uint" + std::to_string(nbpp));
      for (int b = 0; b < 3; ++b) {
        expect_region(path, l, v, b, 0, 0, l.cols, l.rows);
        expect_region(path, l, v, b, 13, 9, 20, 17);   // across blocks
        expect_region(path, l, v, b, 30, 20, 50, 50);  // clipped at the padded edge
      }
    }
}

// IREP RGB marks bands 1 to 3 as red, green and blue (tp-match reads their luminance); a multispectral
// (MULTI) or single-band (MONO) image is no colour image.
TEST(NitfImage, IrepRgbMarksColourBands) {
  for (const char* irep : {"RGB", "MULTI", "MONO"}) {
    Layout l;
    l.bands = std::string(irep) == "MONO" ? 1 : 3;
    l.irep = irep;
    l.nbpp = l.abpp = 8;
    Value v = [](int b, long x, long y) { return std::fmod(pattern(b, x, y), 256.0); };
    const std::string path = write_temp(std::string("irep_") + irep + ".ntf", nitf_bytes(l, image_data(l, v)));
    EXPECT_EQ(image_info(path).rgb, std::string(irep) == "RGB") << irep;
  }
}

TEST(NitfImage, SampleTypesAndJustification) {
  Layout l;
  l.abpp = 11;
  l.pjust = 'L';  // 11 bits at the top of 16-bit words
  Value raw = [](int, long x, long y) { return static_cast<double>(((x * 31 + y * 57) % 2048) << 5); };
  Value val = [](int, long x, long y) { return static_cast<double>((x * 31 + y * 57) % 2048); };
  const std::string left = write_temp("left.ntf", nitf_bytes(l, image_data(l, raw)));
  expect_region(left, l, val, 0, 0, 0, l.cols, l.rows);
  EXPECT_EQ(image_info(left).bits, 11);
  Layout s;
  s.pvtype = "SI";
  Value sv = [](int, long x, long y) { return static_cast<double>(x * 100 - y * 997); };
  Value sv_raw = [](int, long x, long y) { return static_cast<double>(static_cast<uint16_t>(static_cast<int16_t>(x * 100 - y * 997))); };
  const std::string si = write_temp("si.ntf", nitf_bytes(s, image_data(s, sv_raw)));
  EXPECT_EQ(image_info(si).format, "int16");
  expect_region(si, s, sv, 0, 0, 0, s.cols, s.rows);
  Layout f;
  f.pvtype = "R";
  f.nbpp = f.abpp = 32;
  Value fv = [](int, long x, long y) { return 0.25 * x - 3.5 * y; };
  const std::string real = write_temp("real.ntf", nitf_bytes(f, image_data(f, fv)));
  EXPECT_EQ(image_info(real).format, "float");
  expect_region(real, f, fv, 0, 0, 0, f.cols, f.rows);
}

TEST(NitfImage, BlockMaskOutOfOrderAndMissingBlocks) {
  // IC = NM: a block mask table gives each block's offset; blocks stored in reverse order, block 1
  // not stored at all (0xFFFFFFFF): its pixels are the pad value 7, which is the image's nodata
  Layout l;
  l.ic = "NM";
  const long n = nbpr(l) * nbpc(l);
  std::vector<std::string> blocks;
  for (long k = 0; k < n; ++k) blocks.push_back(block_bytes(l, k / nbpr(l), k % nbpr(l), pattern));
  auto be32 = [](uint32_t v) { return std::string{char(v >> 24), char((v >> 16) & 0xFF), char((v >> 8) & 0xFF), char(v & 0xFF)}; };
  const uint32_t header = 4 + 2 + 2 + 2 + 2 + 4 * static_cast<uint32_t>(n);  // 16-bit pad code, one table
  std::string mask = be32(header) + std::string{0, 4} + std::string{0, 0} + std::string{0, 16} + std::string{0, 7};
  std::string stored;
  std::vector<uint32_t> offset(n);
  for (long k = n - 1; k >= 0; --k) {
    if (k == 1) continue;
    offset[k] = static_cast<uint32_t>(stored.size());
    stored += blocks[k];
  }
  offset[1] = 0xFFFFFFFFu;
  for (long k = 0; k < n; ++k) mask += be32(offset[k]);
  const std::string path = write_temp("masked.ntf", nitf_bytes(l, mask + stored));
  Value v = [&](int b, long x, long y) { return (y / l.nppbv == 0 && x / l.nppbh == 1) ? 7.0 : pattern(b, x, y); };
  expect_region(path, l, v, 0, 0, 0, l.cols, l.rows);
  expect_region(path, l, v, 0, 10, 5, 20, 20);
  ASSERT_TRUE(image_info(path).nodata.has_value());
  EXPECT_EQ(*image_info(path).nodata, 7.0);
}

TEST(NitfImage, WriterReadsBack) {
  const long w = 50, h = 37;
  std::vector<uint16_t> px(static_cast<size_t>(w) * h);
  for (long y = 0; y < h; ++y)
    for (long x = 0; x < w; ++x) px[static_cast<size_t>(y) * w + x] = static_cast<uint16_t>((x * 131 + y * 71 + x * y) % 4096);
  for (auto c : {NitfWriteOptions::Compression::none, NitfWriteOptions::Compression::j2k}) {
    const std::string path = testing::TempDir() + (c == NitfWriteOptions::Compression::none ? "w_nc.ntf" : "w_c8.ntf");
    NitfWriteOptions o;
    o.compression = c;
    o.block = 16;
    o.abpp = 12;
    o.tres.push_back(NitfTre{"TESTAA", "hello"});
    {
      NitfWriterU16 wr(path, w, h, o);
      wr.write_rows(0, 10, px.data());
      wr.write_rows(10, h - 10, px.data() + 10 * w);
      wr.close();
    }
    const NitfImage im = read_nitf_image(path);
    EXPECT_EQ(im.ic, c == NitfWriteOptions::Compression::none ? "NC" : "C8");
    EXPECT_EQ(im.abpp, 12);
    EXPECT_EQ(im.nbpr, 4);
    ASSERT_NE(find_nitf_tre(im, "TESTAA"), nullptr);
    EXPECT_EQ(find_nitf_tre(im, "TESTAA")->data, "hello");
    for (auto [x0, y0, rw, rh] : {std::array<long, 4>{0, 0, w, h}, {5, 7, 20, 19}, {33, 30, 40, 40}}) {
      const Raster r = read_region(path, 0, x0, y0, rw, rh);
      for (long y = 0; y < r.height; ++y)
        for (long x = 0; x < r.width; ++x) ASSERT_EQ(r.at(x, y), px[static_cast<size_t>(r.y0 + y) * w + r.x0 + x]) << path;
    }
  }
}

TEST(NitfImage, MalformedFilesRefusedWithWhat) {
  Layout l;
  const std::string good = nitf_bytes(l, image_data(l, pattern));
  // truncated image data
  const std::string cut = write_temp("cut.ntf", good.substr(0, good.size() - 100));
  EXPECT_NE(error_of([&] { read_region(cut, 0, 0, 0, 5, 5); }).find("truncated: the image data ends at byte"), std::string::npos);
  // truncated inside the headers
  const std::string head = write_temp("head.ntf", good.substr(0, 500));
  EXPECT_NE(error_of([&] { image_info(head); }).find("truncated"), std::string::npos);
  // a number field that is not one: NROWS is at byte 404 + 333
  std::string bad = good;
  bad.replace(404 + 333, 8, "00x00029");
  const std::string nrows = write_temp("nrows.ntf", bad);
  EXPECT_NE(error_of([&] { image_info(nrows); }).find("field NROWS at byte 737 is '00x00029', not a number"), std::string::npos);
  // compressions other than NC, NM, C8, M8
  Layout j = l;
  j.ic = "C3";
  const std::string jpeg = write_temp("jpeg.ntf", nitf_bytes(j, "xxxx"));
  EXPECT_NE(error_of([&] { image_info(jpeg); }).find("compression IC=C3 is not supported"), std::string::npos);
  // NITF 2.0
  Layout v20 = l;
  v20.version = "NITF02.00";
  const std::string old = write_temp("v20.ntf", nitf_bytes(v20, image_data(l, pattern)));
  EXPECT_NE(error_of([&] { image_info(old); }).find("only NITF 2.1"), std::string::npos);
  // two image segments: which one is meant is not guessed
  Layout two = l;
  two.image_segments = 2;
  const std::string segs = write_temp("two.ntf", nitf_bytes(two, image_data(l, pattern)));
  EXPECT_NE(error_of([&] { read_band(segs); }).find("2 image segments"), std::string::npos);
  // packed 12-bit samples
  Layout packed = l;
  packed.nbpp = 12;
  packed.abpp = 12;
  const std::string p12 = write_temp("p12.ntf", nitf_bytes(packed, std::string(2000, '\0')));
  EXPECT_NE(error_of([&] { image_info(p12); }).find("NBPP=12: packed samples are not supported"), std::string::npos);
  // C8 whose data is not a codestream
  Layout c8 = l;
  c8.ic = "C8";
  const std::string notj2k = write_temp("notj2k.ntf", nitf_bytes(c8, std::string(64, 'x')));
  EXPECT_NE(error_of([&] { read_band(notj2k); }).find("not a JPEG 2000 codestream"), std::string::npos);
  // a band that does not exist
  const std::string ok = write_temp("ok.ntf", good);
  EXPECT_NE(error_of([&] { read_band(ok, 1); }).find("band 2 does not exist"), std::string::npos);
}

// Issue 50: a JPEG 2000 codestream that lacks tiles (cut at a tile-part boundary, EOC after it) decoded
// them as 0 without a word when a region met tiles that are there too. Every tile the region meets must
// be in the codestream; a region of tiles that are there still reads. (Flipped bytes inside a tile's
// entropy-coded data cannot be told: JPEG 2000 has no checksum over them.)
TEST(NitfImage, Jpeg2000TileMissingRefused) {
  const long w = 50, h = 37;
  std::vector<uint16_t> px(static_cast<size_t>(w) * h);
  for (size_t i = 0; i < px.size(); ++i) px[i] = static_cast<uint16_t>((i * 37) % 4096);
  const std::string path = testing::TempDir() + "tiles.ntf";
  NitfWriteOptions o;
  o.compression = NitfWriteOptions::Compression::j2k;
  o.block = 16;  // 4 x 3 tiles
  o.abpp = 12;
  {
    NitfWriterU16 wr(path, w, h, o);
    wr.write_rows(0, h, px.data());
    wr.close();
  }
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const NitfImage im = read_nitf_image(path);
  // the last tile-part: the last SOT marker of tile 11 (Lsot 10, Isot 11)
  const size_t last = bytes.rfind(std::string("\xFF\x90\x00\x0A\x00\x0B", 6));
  ASSERT_NE(last, std::string::npos);
  ASSERT_GT(last, im.data_offset);
  std::string cut = bytes.substr(0, last) + "\xFF\xD9";
  const uint64_t li = cut.size() - im.data_offset;
  cut.replace(369, 10, num(li, 10));         // LI of the image segment
  cut.replace(342, 12, num(cut.size(), 12));  // FL
  const std::string missing = write_temp("tiles-missing.ntf", cut);
  EXPECT_NE(error_of([&] { read_band(missing); }).find("JPEG 2000: tile 11 (of 12) is not in the codestream"), std::string::npos)
      << error_of([&] { read_band(missing); });
  const Raster r = read_region(missing, 0, 0, 0, 16, 16);  // tile 0
  for (long y = 0; y < 16; ++y)
    for (long x = 0; x < 16; ++x) ASSERT_EQ(r.at(x, y), px[static_cast<size_t>(y) * w + x]);
}
