// The real Pléiades crops' models for the RPC tests (not a test itself: no .cpp): their paths, their
// tag-50844 models as adjustment images, a scratch folder per test program, and the message of a throw.
#pragma once
#include <unistd.h>

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
