// Small in-memory matches files for the interop tests (not a test itself: no .cpp).
#pragma once
#include <filesystem>
#include <random>
#include <string>
#include <vector>
#include <unistd.h>

#include <gtest/gtest.h>

#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"

namespace tpkit_test {

// n records between two images; positions with fractions that float32 cannot hold exactly, ids with
// gaps, one id repeated at a second position in image 2 (as tp-match's per-pair refinement gives),
// and a sigma column.
inline tpkit::Matches sample_matches(const std::string& a, const std::string& b, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1000.0);
  tpkit::Matches m;
  m.source = a + "-" + b;
  m.image1 = {a, 1024, 1000};
  m.image2 = {b, 1028, 1040};
  m.xy.resize(n, 4);
  m.extra.names = {"sigma"};
  m.extra.values.resize(n, 1);
  for (int r = 0; r < n; ++r) {
    m.id1.push_back(3 * r + 1);
    m.id2.push_back(r == n - 1 ? 5 : 5 * r);  // the last record reuses id 5 of image 2 (record 1), elsewhere
    m.xy.row(r) << u(rng) + 1.0 / 3, u(rng), u(rng) + 0.1, u(rng);
    m.extra.values(r, 0) = r % 2 ? 0.05 : 0.4;
  }
  // id 5 a refinement apart from its first position (record 1's)
  if (n > 2) m.xy.row(n - 1).tail<2>() = m.xy.row(1).tail<2>() + Eigen::RowVector2d(0.25, -0.375);
  return m;
}

// A fresh folder for one test, removed when the test program ends.
inline std::string scratch_dir(const std::string& name) {
  struct Cleanup {
    std::vector<std::filesystem::path> dirs;
    ~Cleanup() {
      std::error_code ec;
      for (const auto& d : dirs) std::filesystem::remove_all(d, ec);
    }
  };
  static Cleanup cleanup;
  const auto d = std::filesystem::temp_directory_path() / ("tpkit-interop-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  cleanup.dirs.push_back(d);
  return d.string();
}

inline std::string hex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string h;
  for (unsigned char c : bytes) {
    h += digits[c >> 4];
    h += digits[c & 15];
  }
  return h;
}

inline float f32(double v) { return static_cast<float>(v); }

// `read` must throw InputError whose message names `path` and says `what`.
template <class F>
void expect_input_error(F&& read, const std::string& path, const std::string& what) {
  try {
    read();
    ADD_FAILURE() << path << ": no error (expected: " << what << ")";
  } catch (const tpkit::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

}  // namespace tpkit_test
