// Single points through RPC models and images in the delivery formats (issue 26):
//  - per model: project and localize throughput (points per second, one thread) and the localize ->
//    project round trip's largest error over the validity box (11 x 11 pixels x 5 heights);
//  - per image: it converted to NITF (uncompressed, and lossless JPEG 2000) by tp-rpc's crop, the
//    RPC00B TRE's precision, file sizes, and read times (whole band; 200 random 64 x 64 windows)
//    beside the source, with the pixels compared.
//   build/bin/bench_rpc_points [IMAGE ...]   (default: Marseille img_01.tif and WorldView-3 wv3_20.NTF)
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_crop.hpp"
#include "tpkit/rpc/rpc_io.hpp"

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void model_figures(const std::string& image, const tpkit::RpcModel& m, const tpkit::ImageInfo& info) {
  std::vector<Eigen::Vector3d> ground;
  double worst = 0;
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 10; ++j)
      for (int k = 0; k <= 4; ++k) {
        const double x = (info.width - 1) * i / 10.0, y = (info.height - 1) * j / 10.0;
        const double h = m.height_min() + (m.height_max() - m.height_min()) * k / 4;
        const Eigen::Vector2d ll = m.localize(x, y, h);
        ground.emplace_back(ll.x(), ll.y(), h);
        worst = std::max(worst, (m.project(ll.x(), ll.y(), h) - Eigen::Vector2d(x, y)).norm());
      }
  const int reps = 2000;
  auto t0 = std::chrono::steady_clock::now();
  double sink = 0;
  for (int r = 0; r < reps; ++r)
    for (const auto& g : ground) sink += m.project(g).x();
  const double project_s = seconds_since(t0) / (reps * ground.size());
  t0 = std::chrono::steady_clock::now();
  const int lreps = 20;
  for (int r = 0; r < lreps; ++r)
    for (size_t i = 0; i < ground.size(); ++i) sink += m.localize(100.0 + (i % 50), 50.0 + (i % 37), ground[i].z()).x();
  const double localize_s = seconds_since(t0) / (lreps * ground.size());
  std::printf("%s: project %.2f M points/s, localize %.3f M points/s, localize -> project max %.2e px over %zu points%s\n",
              image.c_str(), 1e-6 / project_s, 1e-6 / localize_s, worst, ground.size(), sink == 12345.678 ? " " : "");
}

// Whole band and random windows: seconds.
std::pair<double, double> read_times(const std::string& path, const tpkit::ImageInfo& info, tpkit::Raster* whole) {
  auto t0 = std::chrono::steady_clock::now();
  *whole = tpkit::read_band(path);
  const double all = seconds_since(t0);
  std::mt19937 rng(7);
  std::uniform_int_distribution<long> ux(0, info.width - 64), uy(0, info.height - 64);
  t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 200; ++i) tpkit::read_region(path, 0, ux(rng), uy(rng), 64, 64);
  return {all, seconds_since(t0)};
}
}  // namespace

int main(int argc, char** argv) {
  const char* usage = "usage: bench_rpc_points [IMAGE ...]\n";
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::fputs(usage, stdout);
    return 0;
  }
  std::vector<std::string> images(argv + 1, argv + argc);
  if (images.empty())
    images = {std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille/img_01.tif", std::string(TPKIT_SHARED_DIR) + "/data/nitf-wv3/wv3_20.NTF"};
  const std::string tmp = (std::filesystem::temp_directory_path() / ("bench_rpc_points." + std::to_string(::getpid()))).string();
  std::filesystem::create_directories(tmp);
  try {
    for (const auto& image : images) {
      const tpkit::RpcSource src = tpkit::load_image_rpc(image);
      const tpkit::ImageInfo info = tpkit::image_info(image);
      model_figures(image, src.model, info);
      tpkit::Raster ref;
      const auto [ref_all, ref_windows] = read_times(image, info, &ref);
      std::printf("  %-26s %10ld bytes  whole band %.4f s  200 windows 64x64 %.4f s\n", ("source (" + info.format + ")").c_str(),
                  static_cast<long>(std::filesystem::file_size(image)), ref_all, ref_windows);
      for (bool j2k : {false, true}) {
        tpkit::CropFormat f;
        f.jpeg2000 = j2k;
        f.block = j2k ? 256 : 1024;
        const std::string out = tmp + (j2k ? "/c8.ntf" : "/nc.ntf");
        auto t0 = std::chrono::steady_clock::now();
        const double change = tpkit::crop_image_with_rpc(image, 0, src.model, 0, 0, info.width, info.height, out, f);
        const double write_s = seconds_since(t0);
        tpkit::Raster back;
        const auto [all, windows] = read_times(out, info, &back);
        std::printf("  %-26s %10ld bytes  whole band %.4f s  200 windows 64x64 %.4f s  written in %.3f s  pixels %s  RPC00B moves the model %.2e px at most\n",
                    j2k ? "NITF C8 (lossless, 256 tiles)" : "NITF NC (1024 blocks)", static_cast<long>(std::filesystem::file_size(out)), all,
                    windows, write_s, back.data == ref.data ? "identical" : "DIFFER", change);
        std::filesystem::remove(out);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_rpc_points: %s\n", e.what());
    std::filesystem::remove_all(tmp);
    return 1;
  }
  std::filesystem::remove_all(tmp);
  return 0;
}
