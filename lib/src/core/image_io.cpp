#include "tpkit/core/image_io.hpp"

#include <OpenImageIO/imageio.h>
#include <tiffio.h>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/nitf_image.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/version.hpp"

namespace tpkit {

using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

namespace {
// Rows [ya, yb) of a single-sample, strip-stored TIFF through libtiff, strip by strip: `row(data, y)`
// gets each row (all columns, native samples). False when the file is not such a TIFF (the caller
// reads it through OIIO). OIIO's scanline reader decodes a compressed strip file from its first row
// at every open, so that reading row y costs y rows; TIFFReadEncodedStrip decodes only the strips asked for.
bool read_tiff_strip_rows(const std::string& path, long width, long ya, long yb, size_t bytes_per_sample,
                          const std::function<void(const unsigned char*, long)>& row);

// The reader's first error, or the global one.
std::string decode_error(ImageInput& in) {
  std::string e = in.geterror();
  if (e.empty()) e = OIIO::geterror();
  if (e.empty()) e = "the decoder failed (truncated or corrupt file?)";
  return e.substr(0, e.find('\n'));  // the first of the decoder's complaints
}

std::unique_ptr<ImageInput> open_input(const std::string& path) {
  check_input_file(path);  // "is a directory", "no such file" (OIIO would say it knows no such format)
  note_input(path);
  auto in = ImageInput::open(path);
  if (!in) {
    std::string err = OIIO::geterror();
    if (err.empty()) err = "cannot open as an image";
    // OIIO messages often repeat the path; keep them short
    if (err.find("not exist") != std::string::npos || err.find("No such file") != std::string::npos)
      err = "no such file";
    else if (err.find("ould not find") != std::string::npos || err.find("format") != std::string::npos ||
             err.find("not a") != std::string::npos)
      err = "not an image file that OpenImageIO can read (" + err + ")";
    throw InputError(path, 0, err);
  }
  return in;
}

}  // namespace

ImageInfo image_info(const std::string& path) {
  if (is_nitf_file(path)) return nitf_image_info(read_nitf_image(path));  // OIIO has no NITF reader
  auto in = open_input(path);
  const ImageSpec& s = in->spec();
  ImageInfo info;
  info.path = path;
  info.width = s.width;
  info.height = s.height;
  info.bands = s.nchannels;
  info.format = s.format.c_str();
  info.bits = s.get_int_attribute("oiio:BitsPerSample", static_cast<int>(s.format.size() * 8));
  std::string nd = s.get_string_attribute("GDAL_NODATA");
  if (!nd.empty()) {
    char* end = nullptr;
    double v = std::strtod(nd.c_str(), &end);
    if (end != nd.c_str()) info.nodata = v;
  }
  in->close();
  return info;
}

Raster read_region(const std::string& path, int band, long x0, long y0, long w, long h) {
  if (is_nitf_file(path)) return read_nitf_region(read_nitf_image(path), band, x0, y0, w, h);
  auto in = open_input(path);
  const ImageSpec& s = in->spec();
  if (band < 0 || band >= s.nchannels)
    throw InputError(path, 0, "band " + std::to_string(band + 1) + " does not exist (the image has " +
                                  std::to_string(s.nchannels) + ")");
  long xa = std::max(0L, x0), ya = std::max(0L, y0);
  long xb = std::min<long>(s.width, x0 + w), yb = std::min<long>(s.height, y0 + h);
  Raster r;
  r.x0 = xa;
  r.y0 = ya;
  r.width = std::max(0L, xb - xa);
  r.height = std::max(0L, yb - ya);
  if (r.width == 0 || r.height == 0) return r;
  r.data.resize(static_cast<size_t>(r.width) * r.height);
  // OIIO would normalize integer data when asked for float: read the native type and convert here,
  // so that values keep the image's own radiometry (e.g. 0..4095 for 12-bit data in 16-bit words).
  const TypeDesc native = s.format;
  const size_t bpp = native.size();
  auto to_float = [&](const unsigned char* src, size_t n, float* dst) {
    for (size_t i = 0; i < n; ++i) {
      const unsigned char* p = src + i * bpp;
      switch (native.basetype) {
        case TypeDesc::UINT8: dst[i] = *p; break;
        case TypeDesc::INT8: dst[i] = *reinterpret_cast<const int8_t*>(p); break;
        case TypeDesc::UINT16: { uint16_t v; std::memcpy(&v, p, 2); dst[i] = v; break; }
        case TypeDesc::INT16: { int16_t v; std::memcpy(&v, p, 2); dst[i] = v; break; }
        case TypeDesc::UINT32: { uint32_t v; std::memcpy(&v, p, 4); dst[i] = static_cast<float>(v); break; }
        case TypeDesc::INT32: { int32_t v; std::memcpy(&v, p, 4); dst[i] = static_cast<float>(v); break; }
        case TypeDesc::FLOAT: std::memcpy(&dst[i], p, 4); break;
        case TypeDesc::DOUBLE: { double v; std::memcpy(&v, p, 8); dst[i] = static_cast<float>(v); break; }
        default: throw InputError(path, 0, std::string("unsupported sample type ") + native.c_str());
      }
    }
  };
  if (s.tile_width == 0 && s.nchannels == 1 &&
      read_tiff_strip_rows(path, s.width, ya, yb, bpp, [&](const unsigned char* row, long y) {
        to_float(row + static_cast<size_t>(xa) * bpp, static_cast<size_t>(r.width), r.data.data() + static_cast<size_t>(y - ya) * r.width);
      })) {
    in->close();
    return r;
  }
  if (s.tile_width > 0) {
    // tiled files: read the tile-aligned cover of the region, keep the region
    const long tw = s.tile_width, th = std::max(1, s.tile_height);
    long ax = (xa / tw) * tw, ay = (ya / th) * th;
    long bx = std::min<long>(s.width, ((xb + tw - 1) / tw) * tw), by = std::min<long>(s.height, ((yb + th - 1) / th) * th);
    std::vector<unsigned char> buf(static_cast<size_t>(bx - ax) * (by - ay) * bpp);
    // a decoder error (a truncated or corrupt compressed tile) is an error even when the call succeeds
    if (!in->read_tiles(0, 0, static_cast<int>(ax), static_cast<int>(bx), static_cast<int>(ay), static_cast<int>(by), 0, 1,
                        band, band + 1, native, buf.data()) ||
        in->has_error())
      throw InputError(path, 0, "read error: " + decode_error(*in));
    for (long yy = ya; yy < yb; ++yy)
      to_float(buf.data() + (static_cast<size_t>(yy - ay) * (bx - ax) + (xa - ax)) * bpp, r.width,
               r.data.data() + static_cast<size_t>(yy - ya) * r.width);
  } else {
    // strips: read full rows a block at a time, keep the columns asked for
    const long block = std::max(1L, std::min<long>(r.height, (1L << 22) / std::max(1, s.width)));
    std::vector<unsigned char> rows(static_cast<size_t>(s.width) * block * bpp);
    for (long y = ya; y < yb; y += block) {
      long ye = std::min(yb, y + block);
      if (!in->read_scanlines(0, 0, static_cast<int>(y), static_cast<int>(ye), 0, band, band + 1, native,
                              rows.data()) ||
          in->has_error())
        throw InputError(path, 0, "read error: " + decode_error(*in));
      for (long yy = y; yy < ye; ++yy)
        to_float(rows.data() + (static_cast<size_t>(yy - y) * s.width + xa) * bpp, r.width,
                 r.data.data() + static_cast<size_t>(yy - ya) * r.width);
    }
  }
  in->close();
  return r;
}

Raster read_band(const std::string& path, int band) {
  ImageInfo info = image_info(path);
  return read_region(path, band, 0, 0, info.width, info.height);
}

struct TiffWriterU16::Impl {
  std::string path, tmp;
  long width = 0, height = 0, next_row = 0;
  std::unique_ptr<ImageOutput> out;
  bool closed = false;
  std::optional<std::array<double, 92>> rpc_tag;
};

namespace {
// libtiff does not define tag 50844 itself: it is registered (as GDAL does) by a tag extender, so that it
// can be written into a file that lacks it and is read with a 32-bit count.
TIFFExtendProc parent_extender = nullptr;
void rpc_tag_extender(TIFF* tif) {
  static const TIFFFieldInfo info[] = {{TIFFTAG_RPCCOEFFICIENT, TIFF_VARIABLE2, TIFF_VARIABLE2, TIFF_DOUBLE, FIELD_CUSTOM,
                                        1, 1, const_cast<char*>("RPCCoefficientTag")}};
  TIFFMergeFieldInfo(tif, info, 1);
  static const TIFFFieldInfo geo[] = {
      {33550, -1, -1, TIFF_DOUBLE, FIELD_CUSTOM, 1, 1, const_cast<char*>("ModelPixelScaleTag")},
      {33922, -1, -1, TIFF_DOUBLE, FIELD_CUSTOM, 1, 1, const_cast<char*>("ModelTiepointTag")},
      {34735, -1, -1, TIFF_SHORT, FIELD_CUSTOM, 1, 1, const_cast<char*>("GeoKeyDirectoryTag")},
      {42113, -1, -1, TIFF_ASCII, FIELD_CUSTOM, 1, 0, const_cast<char*>("GDALNoDataTag")}};
  for (const auto& g : geo)
    if (!TIFFFindField(tif, g.field_tag, TIFF_ANY)) TIFFMergeFieldInfo(tif, &g, 1);
  if (parent_extender) parent_extender(tif);
}
void register_rpc_tag() {
  static std::once_flag once;
  std::call_once(once, [] { parent_extender = TIFFSetTagExtender(rpc_tag_extender); });
  TIFFSetWarningHandler(nullptr);
  TIFFSetErrorHandler(nullptr);
}

// Sets tag 50844 in an existing TIFF file in place (libtiff: OIIO does not write it).
bool read_tiff_strip_rows(const std::string& path, long width, long ya, long yb, size_t bytes_per_sample,
                          const std::function<void(const unsigned char*, long)>& row) {
  register_rpc_tag();  // silences libtiff's warnings on GeoTIFF tags
  TIFF* tif = TIFFOpen(path.c_str(), "r");
  if (!tif) return false;
  uint16_t spp = 1, bits = 0, planar = PLANARCONFIG_CONTIG;
  uint32_t w = 0, rps = 0;
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tif, TIFFTAG_PLANARCONFIG, &planar);
  TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &w);
  TIFFGetFieldDefaulted(tif, TIFFTAG_ROWSPERSTRIP, &rps);
  if (TIFFIsTiled(tif) || spp != 1 || bits != bytes_per_sample * 8 || static_cast<long>(w) != width || rps == 0) {
    TIFFClose(tif);
    return false;
  }
  // A header may declare more samples than the file holds (25 000 x 25 000 floats in 550 bytes): every
  // strip read must lie in the file, and an uncompressed strip is read row by row, only the rows asked
  // for, so that neither a huge declared strip nor a window of a large DEM allocates more than it reads.
  std::error_code ec;
  const uint64_t file_bytes = std::filesystem::file_size(path, ec);
  uint16_t compression = COMPRESSION_NONE;
  TIFFGetFieldDefaulted(tif, TIFFTAG_COMPRESSION, &compression);
  const size_t row_bytes = static_cast<size_t>(width) * bytes_per_sample;
  const uint32_t strips = TIFFNumberOfStrips(tif);
  auto fail = [&](const std::string& why) {
    TIFFClose(tif);
    throw InputError(path, 0, why);
  };
  auto check_strip = [&](long strip) {
    if (strip >= static_cast<long>(strips)) fail("the header declares " + std::to_string(strips) + " strips, row " +
                                                 std::to_string(strip * static_cast<long>(rps)) + " needs more");
    const uint64_t off = TIFFGetStrileOffset(tif, static_cast<uint32_t>(strip)), len = TIFFGetStrileByteCount(tif, static_cast<uint32_t>(strip));
    if (ec || off > file_bytes || len > file_bytes - off)
      fail("strip " + std::to_string(strip) + " lies beyond the end of the file (" + std::to_string(file_bytes) +
           " bytes): a truncated file, or a header declaring more samples than the file holds");
    return std::make_pair(off, len);
  };
  if (compression == COMPRESSION_NONE) {
    std::ifstream in(path, std::ios::binary);
    std::vector<unsigned char> buf(row_bytes);
    for (long y = ya; y < yb; ++y) {
      const long strip = y / static_cast<long>(rps);
      const auto [off, len] = check_strip(strip);
      const uint64_t at = static_cast<uint64_t>(y - strip * static_cast<long>(rps)) * row_bytes;
      if (at + row_bytes > len) fail("strip " + std::to_string(strip) + " is short (truncated file?)");
      in.seekg(static_cast<std::streamoff>(off + at));
      if (!in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(row_bytes)))
        fail("read error at row " + std::to_string(y));
      if (TIFFIsByteSwapped(tif)) {
        if (bytes_per_sample == 2) TIFFSwabArrayOfShort(reinterpret_cast<uint16_t*>(buf.data()), static_cast<tmsize_t>(width));
        else if (bytes_per_sample == 4) TIFFSwabArrayOfLong(reinterpret_cast<uint32_t*>(buf.data()), static_cast<tmsize_t>(width));
        else if (bytes_per_sample == 8) TIFFSwabArrayOfDouble(reinterpret_cast<double*>(buf.data()), static_cast<tmsize_t>(width));
      }
      row(buf.data(), y);
    }
    TIFFClose(tif);
    return true;
  }
  // compressed: a strip is decoded whole; one declared far beyond what a strip may hold is refused
  constexpr tmsize_t kMaxStripBytes = tmsize_t(1) << 30;
  if (TIFFStripSize(tif) > kMaxStripBytes)
    fail("a compressed strip of " + std::to_string(TIFFStripSize(tif) >> 20) + " MiB decoded: larger than 1 GiB (write the file tiled)");
  std::vector<unsigned char> buf(static_cast<size_t>(TIFFStripSize(tif)));
  for (long strip = ya / static_cast<long>(rps); strip * static_cast<long>(rps) < yb; ++strip) {
    check_strip(strip);
    const tmsize_t n = TIFFReadEncodedStrip(tif, static_cast<uint32_t>(strip), buf.data(), static_cast<tmsize_t>(buf.size()));
    if (n < 0) {
      TIFFClose(tif);
      throw InputError(path, 0, "read error: strip " + std::to_string(strip) + " cannot be decoded (truncated or corrupt file?)");
    }
    const long row0 = strip * static_cast<long>(rps), rows = static_cast<long>(static_cast<size_t>(n) / row_bytes);
    for (long y = std::max(ya, row0); y < std::min(yb, row0 + rows); ++y) row(buf.data() + static_cast<size_t>(y - row0) * row_bytes, y);
    if (row0 + rows < std::min(yb, row0 + static_cast<long>(rps))) {
      TIFFClose(tif);
      throw InputError(path, 0, "read error: strip " + std::to_string(strip) + " is short (truncated file?)");
    }
  }
  TIFFClose(tif);
  return true;
}

bool set_rpc_tag_in_place(const std::string& file, const std::array<double, 92>& values) {
  register_rpc_tag();
  TIFF* tif = TIFFOpen(file.c_str(), "r+");
  if (!tif) return false;
  int ok = TIFFSetField(tif, TIFFTAG_RPCCOEFFICIENT, static_cast<uint32_t>(92), values.data()) && TIFFRewriteDirectory(tif);
  TIFFClose(tif);
  return ok != 0;
}
}  // namespace

TiffWriterU16::TiffWriterU16(const std::string& path, long width, long height,
                             const std::vector<std::pair<std::string, std::string>>& tags)
    : impl_(new Impl) {
  impl_->path = path;
  claim_output(path);
  impl_->tmp = claim_temp(path);  // keeps the extension last: OIIO picks the format from it
  impl_->width = width;
  impl_->height = height;
  try {
    impl_->out = ImageOutput::create(impl_->tmp);
    if (!impl_->out) throw InputError(path, 0, "cannot create an image writer: " + OIIO::geterror());
    ImageSpec spec(static_cast<int>(width), static_cast<int>(height), 1, TypeDesc::UINT16);
    // deflate at its fastest level: on noisy 16-bit pixels level 6 (the default) saves 1.7 % of the bytes
    // for 4x the compression time (a 4096² tp-synth view: 22.14 against 22.52 MB, 2.0 against 0.46 s)
    spec.attribute("compression", "zip");
    spec.attribute("tiff:zipquality", 1);
    spec.attribute("tiff:RowsPerStrip", 64);
    spec.attribute("Software", written_by());
    for (const auto& kv : tags) spec.attribute(kv.first, kv.second);
    if (!impl_->out->open(impl_->tmp, spec)) throw InputError(path, 0, "cannot open for writing: " + impl_->out->geterror());
  } catch (...) {
    if (impl_->out) impl_->out->close();
    discard_temp(impl_->tmp);
    throw;
  }
}

TiffWriterU16::~TiffWriterU16() {
  if (!impl_->closed) {
    if (impl_->out) impl_->out->close();
    discard_temp(impl_->tmp);
  }
}

void TiffWriterU16::write_rows(long y0, long rows, const uint16_t* data) {
  if (y0 != impl_->next_row) throw std::logic_error("TiffWriterU16: strips out of order");
  if (!impl_->out->write_scanlines(static_cast<int>(y0), static_cast<int>(y0 + rows), 0, TypeDesc::UINT16, data))
    throw InputError(impl_->path, 0, "write error: " + impl_->out->geterror());
  impl_->next_row = y0 + rows;
}

void TiffWriterU16::set_rpc_tag(const std::array<double, 92>& values) { impl_->rpc_tag = values; }

void TiffWriterU16::close() {
  if (impl_->closed) return;
  if (impl_->next_row != impl_->height) throw std::logic_error("TiffWriterU16: image not complete");
  if (!impl_->out->close()) throw InputError(impl_->path, 0, "write error: " + impl_->out->geterror());
  if (impl_->rpc_tag && !set_rpc_tag_in_place(impl_->tmp, *impl_->rpc_tag))
    throw InputError(impl_->path, 0, "cannot write RPC tag 50844");
  impl_->closed = true;
  finish_output(impl_->tmp, impl_->path);
}

namespace {
template <class T>
void write_whole(const std::string& path, long width, long height, const std::vector<T>& data, TypeDesc type) {
  if (static_cast<long>(data.size()) != width * height) throw std::logic_error("write_image: size mismatch");
  claim_output(path);
  std::string tmp = claim_temp(path);
  auto out = ImageOutput::create(tmp);
  if (!out) {
    discard_temp(tmp);
    throw InputError(path, 0, "cannot create an image writer: " + OIIO::geterror());
  }
  ImageSpec spec(static_cast<int>(width), static_cast<int>(height), 1, type);
  spec.attribute("Software", written_by());
  bool ok = out->open(tmp, spec) && out->write_image(type, data.data()) && out->close();
  if (!ok) {
    std::string err = out->geterror();
    discard_temp(tmp);
    throw InputError(path, 0, "cannot write image" + (err.empty() ? std::string() : ": " + err));
  }
  finish_output(tmp, path);
}
}  // namespace

void write_image_u8(const std::string& path, long width, long height, const std::vector<uint8_t>& data) {
  write_whole(path, width, height, data, TypeDesc::UINT8);
}
void write_image_u16(const std::string& path, long width, long height, const std::vector<uint16_t>& data) {
  write_whole(path, width, height, data, TypeDesc::UINT16);
}

namespace {
// The field type (TIFF type code: 11 FLOAT, 12 DOUBLE, ...) of `tag` in the first directory of a classic or
// Big TIFF, 0 when absent or unreadable. libtiff converts a FLOAT array to the DOUBLE it was registered
// with, silently, so the type on disk is read here.
int tiff_first_ifd_tag_type(const std::string& path, uint16_t tag) {
  std::ifstream in(path, std::ios::binary);
  unsigned char h[16];
  if (!in.read(reinterpret_cast<char*>(h), 16)) return 0;
  const bool le = h[0] == 'I';
  auto u = [&](const unsigned char* p, int n) {
    uint64_t v = 0;
    for (int k = 0; k < n; ++k) v |= uint64_t(p[le ? k : n - 1 - k]) << (8 * k);
    return v;
  };
  const uint64_t magic = u(h + 2, 2);
  if (magic != 42 && magic != 43) return 0;
  const bool big = magic == 43;
  const uint64_t ifd = big ? u(h + 8, 8) : u(h + 4, 4);
  const int count_size = big ? 8 : 2, entry_size = big ? 20 : 12;
  unsigned char c[8];
  if (!in.seekg(static_cast<std::streamoff>(ifd)) || !in.read(reinterpret_cast<char*>(c), count_size)) return 0;
  const uint64_t n = u(c, count_size);
  for (uint64_t e = 0; e < n && e < 65536; ++e) {
    unsigned char d[20];
    if (!in.read(reinterpret_cast<char*>(d), entry_size)) return 0;
    if (u(d, 2) == tag) return static_cast<int>(u(d + 2, 2));
  }
  return 0;
}
}  // namespace

std::optional<RpcTagValues> read_rpc_tag(const std::string& path) {
  register_rpc_tag();
  note_input(path);
  TIFF* tif = TIFFOpen(path.c_str(), "r");
  if (!tif) throw InputError(path, 0, "not a TIFF file (no RPC tag can be read)");
  uint32_t count = 0;
  double* v = nullptr;
  int ok = TIFFGetField(tif, TIFFTAG_RPCCOEFFICIENT, &count, &v);
  std::optional<RpcTagValues> out;
  if (ok) {
    if (count != 92 || !v) {
      TIFFClose(tif);
      throw InputError(path, 0, "RPC tag 50844 holds " + std::to_string(count) + " values instead of 92");
    }
    RpcTagValues r;
    std::copy(v, v + 92, r.begin());
    out = r;
  }
  TIFFClose(tif);
  if (out) {
    const int type = tiff_first_ifd_tag_type(path, TIFFTAG_RPCCOEFFICIENT);
    if (type != 0 && type != TIFF_DOUBLE)
      throw InputError(path, 0, "RPC tag 50844 is stored as " + std::string(type == TIFF_FLOAT ? "FLOAT" : "TIFF type " + std::to_string(type)) +
                                    ", not DOUBLE: its values have lost their precision (give the model in a sidecar or with --rpc)");
  }
  return out;
}

void copy_tiff_with_rpc_tag(const std::string& src, const std::string& dst, const RpcTagValues& values) {
  note_input(src);
  claim_output(dst);
  std::string tmp = claim_temp(dst);
  auto fail = [&](const std::string& why) {
    discard_temp(tmp);
    throw InputError(dst, 0, why);
  };
  {
    std::FILE* in = std::fopen(src.c_str(), "rb");
    if (!in) {
      discard_temp(tmp);
      throw InputError(src, 0, "cannot open");
    }
    std::FILE* out = std::fopen(tmp.c_str(), "wb");
    if (!out) {
      std::fclose(in);
      fail("cannot create");
    }
    char buf[1 << 16];
    size_t n;
    bool ok = true;
    while ((n = std::fread(buf, 1, sizeof buf, in)) > 0) ok = ok && std::fwrite(buf, 1, n, out) == n;
    ok = ok && !std::ferror(in);
    std::fclose(in);
    ok = (std::fclose(out) == 0) && ok;
    if (!ok) fail("cannot copy " + src);
  }
  if (!set_rpc_tag_in_place(tmp, values)) {
    discard_temp(tmp);
    throw InputError(src, 0, "not a TIFF file, or its RPC tag 50844 cannot be written");
  }
  finish_output(tmp, dst);
}

void write_geotiff_grid(const std::string& path, const GeoGrid& g) {
  if (g.width <= 0 || g.height <= 0 || static_cast<long>(g.data.size()) != g.width * g.height)
    throw std::logic_error("write_geotiff_grid: size mismatch");
  register_rpc_tag();
  claim_output(path);
  std::string tmp = claim_temp(path);
  TIFF* tif = TIFFOpen(tmp.c_str(), "w");
  if (!tif) {
    discard_temp(tmp);
    throw InputError(path, 0, "cannot create");
  }
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(g.width));
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(g.height));
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 32);
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
  TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 16);
  TIFFSetField(tif, TIFFTAG_SOFTWARE, written_by().c_str());
  const double scale[3] = {g.dlon, g.dlat, 0};
  const double tie[6] = {0, 0, 0, g.lon0, g.lat0, 0};
  // GeoKeys: version 1.1.0, 4 keys: GTModelType = 2 (geographic), GTRasterType = 2 (PixelIsPoint),
  // GeographicType = 4326 (WGS 84), GeogAngularUnits = 9102 (degree)
  const uint16_t keys[] = {1, 1, 0, 4, 1024, 0, 1, 2, 1025, 0, 1, 2, 2048, 0, 1, 4326, 2054, 0, 1, 9102};
  bool ok = TIFFSetField(tif, 33550, 3, scale) && TIFFSetField(tif, 33922, 6, tie) &&
            TIFFSetField(tif, 34735, static_cast<int>(sizeof keys / sizeof keys[0]), keys);
  for (long y = 0; ok && y < g.height; ++y)
    ok = TIFFWriteScanline(tif, const_cast<float*>(g.data.data() + y * g.width), static_cast<uint32_t>(y), 0) == 1;
  TIFFClose(tif);
  if (!ok) {
    discard_temp(tmp);
    throw InputError(path, 0, "cannot write the GeoTIFF");
  }
  finish_output(tmp, path);
}

GeoGrid read_geotiff_grid(const std::string& path, const GeoBounds* within) {
  // georeferencing through libtiff (OIIO does not expose the GeoTIFF tags), pixels through OIIO
  register_rpc_tag();
  note_input(path);
  TIFF* tif = TIFFOpen(path.c_str(), "r");
  if (!tif) throw InputError(path, 0, "not a TIFF file (a DEM must be a GeoTIFF)");
  auto doubles = [&](uint32_t tag, uint32_t n, double* out) {
    uint16_t count = 0;
    double* v = nullptr;
    if (!TIFFGetField(tif, tag, &count, &v) || !v || count < n) return false;
    std::copy(v, v + n, out);
    return true;
  };
  double scale[3], tie[6];
  bool geo = doubles(33550, 3, scale) && doubles(33922, 6, tie);
  std::map<int, int> keys;
  uint16_t nk = 0;
  uint16_t* k = nullptr;
  if (TIFFGetField(tif, 34735, &nk, &k) && k && nk >= 4)
    for (int e = 0; e < k[3] && 4 + 4 * e + 3 < nk; ++e)
      if (k[4 + 4 * e + 1] == 0) keys[k[4 + 4 * e]] = k[4 + 4 * e + 3];
  // GDAL's no-data value (tag 42113, ASCII): a sample equal to it is no height
  std::optional<double> nodata;
  char* nd = nullptr;
  if (TIFFGetField(tif, 42113, &nd) && nd) {
    std::string t(nd);
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    while (end && *end && std::isspace(static_cast<unsigned char>(*end))) ++end;
    if (end == t.c_str() || (end && *end)) {
      TIFFClose(tif);
      throw InputError(path, 0, "GDAL_NODATA tag 42113: '" + t + "' is not a number");
    }
    nodata = v;
  }
  TIFFClose(tif);
  if (!geo) throw InputError(path, 0, "no GeoTIFF georeferencing (ModelPixelScale and ModelTiepoint tags)");
  auto key = [&](int id, int def) { return keys.count(id) ? keys[id] : def; };
  int model = key(1024, 0), geog = key(2048, 0);
  if (model != 2 || geog != 4326)
    throw InputError(path, 0, "the DEM must be in geographic WGS 84 coordinates (EPSG:4326); GTModelType " +
                                  std::to_string(model) + ", GeographicType " + std::to_string(geog));
  if (!(scale[0] > 0) || !(scale[1] > 0)) throw InputError(path, 0, "ModelPixelScale must be positive");
  GeoGrid g;
  g.dlon = scale[0];
  g.dlat = scale[1];
  // the tie point maps raster (I, J) to (lon, lat); PixelIsArea (1, the default) puts raster (0, 0) at the
  // corner of the first sample, PixelIsPoint (2) at its centre
  double shift = key(1025, 1) == 2 ? 0.0 : 0.5;
  g.lon0 = tie[3] + (shift - tie[0]) * g.dlon;
  g.lat0 = tie[4] - (shift - tie[1]) * g.dlat;
  // the samples within the bounds (and two beyond, for interpolation), clipped to the grid: a DEM of a
  // country is not read whole for one scene, and a header declaring more samples than the file holds
  // fails on the part that is read
  const ImageInfo info = image_info(path);
  long x0 = 0, y0 = 0, x1 = info.width, y1 = info.height;
  if (within) {
    x0 = std::max(0L, static_cast<long>(std::floor((within->lon0 - g.lon0) / g.dlon)) - 2);
    x1 = std::min(info.width, static_cast<long>(std::ceil((within->lon1 - g.lon0) / g.dlon)) + 3);
    y0 = std::max(0L, static_cast<long>(std::floor((g.lat0 - within->lat1) / g.dlat)) - 2);
    y1 = std::min(info.height, static_cast<long>(std::ceil((g.lat0 - within->lat0) / g.dlat)) + 3);
    if (x1 <= x0 || y1 <= y0)
      throw InputError(path, 0, "the DEM (lon " + format_number(g.lon0) + " .. " + format_number(g.lon0 + (info.width - 1) * g.dlon) +
                                    ", lat " + format_number(g.lat0 - (info.height - 1) * g.dlat) + " .. " + format_number(g.lat0) +
                                    ") does not cover the scene (lon " + format_number(within->lon0) + " .. " +
                                    format_number(within->lon1) + ", lat " + format_number(within->lat0) + " .. " +
                                    format_number(within->lat1) + ")");
  }
  constexpr long kMaxSamples = 400L * 1000 * 1000;
  if ((x1 - x0) > kMaxSamples / std::max(1L, y1 - y0))
    throw InputError(path, 0, "the DEM window of " + std::to_string(x1 - x0) + " x " + std::to_string(y1 - y0) +
                                  " samples is larger than " + std::to_string(kMaxSamples) + " samples");
  Raster r = read_region(path, 0, x0, y0, x1 - x0, y1 - y0);
  g.lon0 += x0 * g.dlon;
  g.lat0 -= y0 * g.dlat;
  g.width = r.width;
  g.height = r.height;
  g.data = std::move(r.data);
  if (nodata)
    for (float& v : g.data)
      if (v == static_cast<float>(*nodata)) v = NAN;
  return g;
}

}  // namespace tpkit
