// The interface between tpkit's core and its OpenImageIO module (lib/modules/oiio/tpkit_oiio.cpp, built as
// tpkit_oiio.so): plain functions over tpkit-free types, so that the module links OpenImageIO only and
// shares no state with the core that loads it. Both sides are built together; kVersion changes with any
// change here.
#pragma once
#include <string>

namespace tpkit::oiio_abi {

constexpr int kVersion = 1;

struct Info {
  long width = 0, height = 0;
  int bands = 0, bits = 0;
  char format[16] = {};  // "uint8", "uint16", "float", ...
  bool has_nodata = false;
  double nodata = 0;
};

// Each returns false with the reason in *err (the path not repeated).
struct Api {
  int version;
  bool (*info)(const char* path, Info* out, std::string* err);
  // Band `band` of the region [x0, x0 + w) x [y0, y0 + h), inside the image, into out (w * h floats,
  // row-major), the samples' own values (no normalisation).
  bool (*read)(const char* path, int band, long x0, long y0, long w, long h, float* out, std::string* err);
  // A single-band image of `bits` 8 or 16 in the format of the path's extension.
  bool (*write)(const char* path, long w, long h, int bits, const void* data, const char* software, std::string* err);
};

}  // namespace tpkit::oiio_abi

extern "C" const tpkit::oiio_abi::Api* tpkit_oiio_api();
