#include "tpkit/core/oiio_images.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <mutex>

#include "oiio_module_abi.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/version.hpp"

#ifndef TPKIT_OIIO_MODULE_REL
#define TPKIT_OIIO_MODULE_REL "../lib/tpkit/tpkit_oiio.so"
#endif
#ifndef TPKIT_OIIO_MODULE_INSTALLED
#define TPKIT_OIIO_MODULE_INSTALLED "/usr/local/lib/tpkit/tpkit_oiio.so"
#endif

namespace tpkit {

std::vector<std::string> oiio_module_candidates() {
  std::vector<std::string> c;
  if (const char* env = std::getenv("TPKIT_OIIO_MODULE"); env && *env) c.push_back(env);
  char exe[4096];
  const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n > 0) {
    std::string dir(exe, static_cast<size_t>(n));
    dir = dir.substr(0, dir.rfind('/'));
    c.push_back(dir + "/" + TPKIT_OIIO_MODULE_REL);
  }
  c.push_back(TPKIT_OIIO_MODULE_INSTALLED);
  return c;
}

namespace {
// The module's functions, loaded once per process; null with the reasons when it cannot be loaded.
const oiio_abi::Api* module_api(std::string* why) {
  static std::once_flag once;
  static const oiio_abi::Api* api = nullptr;
  static std::string reasons;
  std::call_once(once, [] {
    for (const std::string& path : oiio_module_candidates()) {
      if (::access(path.c_str(), F_OK) != 0) {
        reasons += (reasons.empty() ? "" : "; ") + path + ": no such file";
        continue;
      }
      void* h = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!h) {
        const char* e = ::dlerror();
        reasons += (reasons.empty() ? "" : "; ") + std::string(e ? e : path + ": cannot be loaded");
        continue;
      }
      auto get = reinterpret_cast<const oiio_abi::Api* (*)()>(::dlsym(h, "tpkit_oiio_api"));
      const oiio_abi::Api* a = get ? get() : nullptr;
      if (!a || a->version != oiio_abi::kVersion) {
        reasons += (reasons.empty() ? "" : "; ") + path + ": not this tpkit's module (another version?)";
        continue;
      }
      api = a;
      return;
    }
  });
  *why = reasons;
  return api;
}

const oiio_abi::Api& api_for(const std::string& path) {
  std::string why;
  const oiio_abi::Api* a = module_api(&why);
  if (!a)
    throw InputError(path, 0, "neither TIFF nor NITF: other formats are read through tpkit's OpenImageIO module, which cannot be loaded (" +
                                  why + ")");
  return *a;
}
}  // namespace

ImageInfo oiio_image_info(const std::string& path) {
  const oiio_abi::Api& a = api_for(path);
  oiio_abi::Info i;
  std::string err;
  if (!a.info(path.c_str(), &i, &err)) throw InputError(path, 0, err);
  ImageInfo info;
  info.path = path;
  info.width = i.width;
  info.height = i.height;
  info.bands = i.bands;
  info.format = i.format;
  info.bits = i.bits;
  info.rgb = i.bands == 3 || i.bands == 4;  // these formats' colour images: RGB, RGBA
  if (i.has_nodata) info.nodata = i.nodata;
  return info;
}

Raster oiio_read_region(const std::string& path, int band, long x0, long y0, long w, long h) {
  const ImageInfo info = oiio_image_info(path);
  Raster r = clipped_raster(path, info.width, info.height, info.bands, band, x0, y0, w, h);
  if (r.data.empty()) return r;
  std::string err;
  if (!api_for(path).read(path.c_str(), band, r.x0, r.y0, r.width, r.height, r.data.data(), &err)) throw InputError(path, 0, err);
  return r;
}

void oiio_write_image(const std::string& file, const std::string& path, long width, long height, int bits, const void* data) {
  std::string err;
  if (!api_for(path).write(file.c_str(), width, height, bits, data, written_by().c_str(), &err)) throw InputError(path, 0, err);
}

}  // namespace tpkit
