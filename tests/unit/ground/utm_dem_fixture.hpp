// What the ground unit tests share (not a test itself: no .cpp): a scratch folder per test program, UTM 31N
// <-> WGS 84 through PROJ (independent of the reader's own path through it), and a DEM raster of a surface
// z(e, n) on a UTM 31N grid.
#pragma once
#include <proj.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>

#include "tpkit/ground/reference_dem.hpp"

namespace tpkit_test {

// A file in this test program's own scratch folder (`program` names it, with the process id).
inline std::string scratch(const std::string& program, const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("tpkit_" + program + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

struct Utm31 {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* raw = proj_create_crs_to_crs(ctx, "EPSG:4326", "EPSG:32631", nullptr);
  PJ* pj = proj_normalize_for_visualization(ctx, raw);
  Utm31() = default;
  Utm31(const Utm31&) = delete;
  Utm31& operator=(const Utm31&) = delete;
  ~Utm31() {
    proj_destroy(pj);
    proj_destroy(raw);
    proj_context_destroy(ctx);
  }
  void lonlat(double e, double n, double& lon, double& lat) const {
    const PJ_COORD q = proj_trans(pj, PJ_INV, proj_coord(e, n, 0, 0));
    lon = q.lp.lam;
    lat = q.lp.phi;
  }
  void forward(double lon, double lat, double& e, double& n) const {
    const PJ_COORD q = proj_trans(pj, PJ_FWD, proj_coord(lon, lat, 0, 0));
    e = q.xy.x;
    n = q.xy.y;
  }
};

// The surface z(e, n) sampled on a UTM 31N grid: top-left sample centre (e0, n0), `posting` m, w x h cells.
inline tpkit::DemRaster utm_raster(double e0, double n0, double posting, long w, long h,
                                   const std::function<double(double, double)>& z, const std::string& datum, int tile) {
  tpkit::DemRaster r;
  r.epsg = 32631;
  r.x0 = e0;
  r.y0 = n0;
  r.dx = r.dy = posting;
  r.width = w;
  r.height = h;
  r.datum = datum;
  r.tile = tile;
  r.data.resize(static_cast<size_t>(w * h));
  for (long y = 0; y < h; ++y)
    for (long x = 0; x < w; ++x) r.data[static_cast<size_t>(y * w + x)] = static_cast<float>(z(e0 + x * posting, n0 - y * posting));
  return r;
}

}  // namespace tpkit_test
