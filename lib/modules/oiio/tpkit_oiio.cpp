// tpkit's OpenImageIO module: image formats other than TIFF and NITF (PNG, JPEG, OpenEXR, ...), loaded by
// the core on first use (lib/include/tpkit/core/oiio_images.hpp). Links OpenImageIO only.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "../../src/core/oiio_module_abi.hpp"

namespace {
using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;
namespace abi = tpkit::oiio_abi;

// The reader's first error, or the global one, first line only.
std::string decode_error(ImageInput& in) {
  std::string e = in.geterror();
  if (e.empty()) e = OIIO::geterror();
  if (e.empty()) e = "the decoder failed (truncated or corrupt file?)";
  return e.substr(0, e.find('\n'));
}

std::unique_ptr<ImageInput> open_input(const char* path, std::string* err) {
  auto in = ImageInput::open(path);
  if (!in) {
    std::string e = OIIO::geterror();
    if (e.empty()) e = "cannot open as an image";
    // OIIO messages often repeat the path; keep them short
    if (e.find("not exist") != std::string::npos || e.find("No such file") != std::string::npos)
      e = "no such file";
    else if (e.find("ould not find") != std::string::npos || e.find("format") != std::string::npos || e.find("not a") != std::string::npos)
      e = "not an image file that OpenImageIO can read (" + e.substr(0, e.find('\n')) + ")";
    *err = e;
  }
  return in;
}

std::string type_name(TypeDesc t) {
  switch (t.basetype) {
    case TypeDesc::UINT32: return "uint32";
    case TypeDesc::INT32: return "int32";
    default: return t.c_str();
  }
}

bool info(const char* path, abi::Info* out, std::string* err) {
  auto in = open_input(path, err);
  if (!in) return false;
  const ImageSpec& s = in->spec();
  out->width = s.width;
  out->height = s.height;
  out->bands = s.nchannels;
  std::string f = type_name(s.format);
  f.copy(out->format, sizeof out->format - 1);
  out->bits = s.get_int_attribute("oiio:BitsPerSample", static_cast<int>(s.format.size() * 8));
  std::string nd = s.get_string_attribute("GDAL_NODATA");
  if (!nd.empty()) {
    char* end = nullptr;
    double v = std::strtod(nd.c_str(), &end);
    if (end != nd.c_str()) out->has_nodata = true, out->nodata = v;
  }
  in->close();
  return true;
}

bool read(const char* path, int band, long xa, long ya, long w, long h, float* out, std::string* err) {
  auto in = open_input(path, err);
  if (!in) return false;
  const ImageSpec& s = in->spec();
  if (band < 0 || band >= s.nchannels || xa < 0 || ya < 0 || xa + w > s.width || ya + h > s.height) {
    *err = "region or band outside the image";
    return false;
  }
  const long xb = xa + w, yb = ya + h;
  // OIIO would normalize integer data when asked for float: read the native type and convert here,
  // so that values keep the image's own radiometry.
  // (half floats are converted to float by OIIO, exactly)
  const TypeDesc native = s.format.basetype == TypeDesc::HALF ? TypeDesc(TypeDesc::FLOAT) : s.format;
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
        default: return false;
      }
    }
    return true;
  };
  if (s.tile_width > 0) {
    // tiled files: read the tile-aligned cover of the region, keep the region
    const long tw = s.tile_width, th = std::max(1, s.tile_height);
    long ax = (xa / tw) * tw, ay = (ya / th) * th;
    long bx = std::min<long>(s.width, ((xb + tw - 1) / tw) * tw), by = std::min<long>(s.height, ((yb + th - 1) / th) * th);
    std::vector<unsigned char> buf(static_cast<size_t>(bx - ax) * (by - ay) * bpp);
    // a decoder error (a truncated or corrupt compressed tile) is an error even when the call succeeds
    if (!in->read_tiles(0, 0, static_cast<int>(ax), static_cast<int>(bx), static_cast<int>(ay), static_cast<int>(by), 0, 1, band, band + 1,
                        native, buf.data()) ||
        in->has_error()) {
      *err = "read error: " + decode_error(*in);
      return false;
    }
    for (long yy = ya; yy < yb; ++yy)
      if (!to_float(buf.data() + (static_cast<size_t>(yy - ay) * (bx - ax) + (xa - ax)) * bpp, w, out + static_cast<size_t>(yy - ya) * w)) {
        *err = std::string("unsupported sample type ") + native.c_str();
        return false;
      }
  } else {
    // scanlines: full rows a block at a time, keep the columns asked for
    const long block = std::max(1L, std::min<long>(h, (1L << 22) / std::max(1, s.width)));
    std::vector<unsigned char> rows(static_cast<size_t>(s.width) * block * bpp);
    for (long y = ya; y < yb; y += block) {
      long ye = std::min(yb, y + block);
      if (!in->read_scanlines(0, 0, static_cast<int>(y), static_cast<int>(ye), 0, band, band + 1, native, rows.data()) || in->has_error()) {
        *err = "read error: " + decode_error(*in);
        return false;
      }
      for (long yy = y; yy < ye; ++yy)
        if (!to_float(rows.data() + (static_cast<size_t>(yy - y) * s.width + xa) * bpp, w, out + static_cast<size_t>(yy - ya) * w)) {
          *err = std::string("unsupported sample type ") + native.c_str();
          return false;
        }
    }
  }
  in->close();
  return true;
}

bool write(const char* path, long w, long h, int bits, const void* data, const char* software, std::string* err) {
  auto out = ImageOutput::create(path);
  if (!out) {
    *err = "cannot create an image writer: " + OIIO::geterror();
    return false;
  }
  const TypeDesc type = bits == 8 ? TypeDesc::UINT8 : TypeDesc::UINT16;
  ImageSpec spec(static_cast<int>(w), static_cast<int>(h), 1, type);
  spec.attribute("Software", software);
  if (!(out->open(path, spec) && out->write_image(type, data) && out->close())) {
    std::string e = out->geterror();
    *err = "cannot write image" + (e.empty() ? std::string() : ": " + e.substr(0, e.find('\n')));
    return false;
  }
  return true;
}

const abi::Api kApi{abi::kVersion, info, read, write};
}  // namespace

extern "C" __attribute__((visibility("default"))) const tpkit::oiio_abi::Api* tpkit_oiio_api() { return &kApi; }
