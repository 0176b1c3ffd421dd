// The real Pléiades crops' models for the RPC tests (not a test itself: no .cpp): their paths, their
// tag-50844 models as adjustment images, a scratch folder per test program, and the message of a throw.
#pragma once
#include <unistd.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_io.hpp"

namespace tpkit_test {

// A file in this test program's own scratch folder (`program` names it, with the process id).
inline std::filesystem::path scratch(const std::string& program, const std::string& name) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() / ("tpkit-" + program + "-" + std::to_string(::getpid()));
  std::filesystem::create_directories(d);
  return d / name;
}

inline const std::string kPleiades = std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille";
// img_0i.tif, i = 1..3
inline std::string pleiades_image(int i) { return kPleiades + "/img_0" + std::to_string(i) + ".tif"; }

// The three crops with their tag-50844 models and sizes, none fixed.
inline std::vector<tpkit::AdjustImage> pleiades_images() {
  std::vector<tpkit::AdjustImage> out;
  for (int i = 1; i <= 3; ++i) {
    auto m = tpkit::read_rpc_tiff(pleiades_image(i));
    if (!m) throw std::runtime_error("no RPC tag in the Pléiades crop");
    const tpkit::ImageInfo info = tpkit::image_info(pleiades_image(i));
    out.push_back({pleiades_image(i), info.width, info.height, *m, false});
  }
  return out;
}

// A smooth terrain over a model's validity box (m above the ellipsoid): 150 m +- 60 m of hills.
inline double smooth_terrain(const tpkit::RpcModel& m, double lon, double lat) {
  const double u = (lon - m.lon_off) / m.lon_scale, v = (lat - m.lat_off) / m.lat_scale;
  return 150 + 40 * std::sin(3.1 * u + 0.4) * std::cos(2.3 * v) + 20 * u * v;
}

// Ground truth for the adjustment tests: three images, a bias per image, ground points on smooth_terrain and
// their observed (biased) pixels, observed = bias(rpc(g)) (x column, y row).
struct BiasedTruth {
  std::vector<tpkit::AdjustImage> images;
  std::vector<tpkit::ImageBias> bias;                     // injected, per image
  std::vector<Eigen::Vector3d> ground;                    // per point: lon, lat, h
  std::vector<std::array<Eigen::Vector2d, 3>> xy;        // observed pixel per point and image
};

// Adds n x n ground points over image 1 (from `margin` pixels of its edges, margin_x across, margin_y down),
// each where image 1's ray meets smooth_terrain, kept when all three images see it 5 px inside their edges.
inline void add_grid_points(BiasedTruth& T, int n, double margin_x, double margin_y) {
  const tpkit::RpcModel& m = T.images[0].model;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const double x = margin_x + a * (T.images[0].width - 2 * margin_x) / (n - 1);
      const double y = margin_y + b * (T.images[0].height - 2 * margin_y) / (n - 1);
      Eigen::Vector2d ll = m.localize(x, y, 150);
      for (int it = 0; it < 5; ++it) ll = m.localize(x, y, smooth_terrain(m, ll[0], ll[1]));
      const Eigen::Vector3d g(ll[0], ll[1], smooth_terrain(m, ll[0], ll[1]));
      std::array<Eigen::Vector2d, 3> p;
      bool on = true;
      for (int i = 0; i < 3; ++i) {
        p[i] = T.bias[i].apply(T.images[i].model.project(g));
        on = on && p[i][0] > 5 && p[i][1] > 5 && p[i][0] < T.images[i].width - 5 && p[i][1] < T.images[i].height - 5;
      }
      if (!on) continue;
      T.ground.push_back(g);
      T.xy.push_back(p);
    }
}

// What f throws (its what()), or "" when it throws nothing.
inline std::string message(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace tpkit_test
