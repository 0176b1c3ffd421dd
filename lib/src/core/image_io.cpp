#include "tpkit/image_io.hpp"

#include <OpenImageIO/imageio.h>
#include <tiffio.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "tpkit/atomic_output.hpp"
#include "tpkit/error.hpp"
#include "tpkit/version.hpp"

namespace tpkit {

using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

namespace {
// The reader's first error, or the global one.
std::string decode_error(ImageInput& in) {
  std::string e = in.geterror();
  if (e.empty()) e = OIIO::geterror();
  if (e.empty()) e = "the decoder failed (truncated or corrupt file?)";
  return e.substr(0, e.find('\n'));  // the first of the decoder's complaints
}

std::unique_ptr<ImageInput> open_input(const std::string& path) {
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
};

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
    spec.attribute("compression", "zip");
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

void TiffWriterU16::close() {
  if (impl_->closed) return;
  if (impl_->next_row != impl_->height) throw std::logic_error("TiffWriterU16: image not complete");
  if (!impl_->out->close()) throw InputError(impl_->path, 0, "write error: " + impl_->out->geterror());
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
// RPC00B term order of the 20 cubic monomials in normalized (P = lat, L = lon, H = height).
double rpc_poly(const std::array<double, 20>& c, double L, double P, double H) {
  const double t[20] = {1,         L,         P,         H,         L * P,     L * H,     P * H,
                        L * L,     P * P,     H * H,     P * L * H, L * L * L, L * P * P, L * H * H,
                        L * L * P, P * P * P, P * H * H, L * L * H, P * P * H, H * H * H};
  double s = 0;
  for (int i = 0; i < 20; ++i) s += c[i] * t[i];
  return s;
}
}  // namespace

std::array<double, 2> Rpc::project(double lon, double lat, double h) const {
  double L = (lon - lon_off) / lon_scale, P = (lat - lat_off) / lat_scale, H = (h - height_off) / height_scale;
  double line = rpc_poly(line_num, L, P, H) / rpc_poly(line_den, L, P, H) * line_scale + line_off;
  double samp = rpc_poly(samp_num, L, P, H) / rpc_poly(samp_den, L, P, H) * samp_scale + samp_off;
  return {samp, line};
}

std::array<double, 2> Rpc::localize(double x, double y, double h) const {
  double lon = lon_off, lat = lat_off;
  const double d = 1e-7;
  for (int it = 0; it < 50; ++it) {
    auto f = project(lon, lat, h);
    double rx = x - f[0], ry = y - f[1];
    if (std::hypot(rx, ry) < 1e-9) return {lon, lat};
    auto fl = project(lon + d, lat, h), fp = project(lon, lat + d, h);
    double a = (fl[0] - f[0]) / d, b = (fp[0] - f[0]) / d, c = (fl[1] - f[1]) / d, e = (fp[1] - f[1]) / d;
    double det = a * e - b * c;
    if (!(std::fabs(det) > 0)) break;
    lon += (e * rx - b * ry) / det;
    lat += (-c * rx + a * ry) / det;
  }
  auto f = project(lon, lat, h);
  if (std::hypot(x - f[0], y - f[1]) < 1e-6) return {lon, lat};
  throw NumericalError("RPC localization did not converge");
}

std::optional<Rpc> read_rpc(const std::string& path) {
  TIFFSetWarningHandler(nullptr);
  TIFFSetErrorHandler(nullptr);
  TIFF* tif = TIFFOpen(path.c_str(), "r");
  if (!tif) throw InputError(path, 0, "not a TIFF file (no RPC tag can be read)");
  uint32_t count = 0;
  double* v = nullptr;
  int ok = TIFFGetField(tif, TIFFTAG_RPCCOEFFICIENT, &count, &v);
  std::optional<Rpc> out;
  if (ok) {
    if (count != 92 || !v) {
      TIFFClose(tif);
      throw InputError(path, 0, "RPC tag 50844 holds " + std::to_string(count) + " values instead of 92");
    }
    Rpc r;
    r.err_bias = v[0];
    r.err_rand = v[1];
    r.line_off = v[2];
    r.samp_off = v[3];
    r.lat_off = v[4];
    r.lon_off = v[5];
    r.height_off = v[6];
    r.line_scale = v[7];
    r.samp_scale = v[8];
    r.lat_scale = v[9];
    r.lon_scale = v[10];
    r.height_scale = v[11];
    for (int i = 0; i < 20; ++i) {
      r.line_num[i] = v[12 + i];
      r.line_den[i] = v[32 + i];
      r.samp_num[i] = v[52 + i];
      r.samp_den[i] = v[72 + i];
    }
    out = r;
  }
  TIFFClose(tif);
  return out;
}

}  // namespace tpkit
