// rpc-adjust benchmark: the time of adjust_rpcs (initial intersections, Ceres solve, residuals) on
//   1. a synthetic triplet, 3 images x 7000 three-view tracks (tp-synth's default scene, 0.1 px noise);
//   2. 50 synthetic images x 100000 tracks of 2..5 views each, on 2 threads (progress line on a terminal);
//   3. optionally real tracks: bench_rpc_adjust TRACKS IMAGE1 IMAGE2 IMAGE3 (e.g. the Marseille triplet
//      from the README's tour; the models are the images' own).
// Each case prints its size, the seconds, and the RMS residual before / after.
//   build*/bin/bench_rpc_adjust [TRACKS IMAGE...]
#include <unistd.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/synth/synth_camera.hpp"
#include "tpkit/synth/synth_rpc.hpp"
#include "tpkit/synth/synth_scene.hpp"

using namespace tpkit;

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void report(const char* name, size_t images, size_t tracks, const AdjustResult& r, double s) {
  std::printf("%-34s %3zu images %7zu tracks %8zu observations: %7.3f s, rms %.4f px before, %.4f px after, %d iterations\n",
              name, images, tracks, r.obs_image.size(), s, residual_rms(r, false), residual_rms(r, true), r.iterations);
  std::fflush(stdout);
}

// `n` affine cameras over the default scene, seen from directions spread over +-20 deg along and +-15 deg
// across track, each with its RPC (biased by a random shift up to 5 px and affine terms up to 1e-4).
struct Synthetic {
  SynthScene scene{SynthParams{}};
  SynthGeoFrame geo{scene, SynthGeoOrigin{}};
  std::vector<SynthCamera> cams;
  std::vector<AdjustImage> images;
};

void make_cameras(Synthetic& s, int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  const double S = s.scene.scene_size();
  const long size = s.scene.params().size;
  for (int i = 0; i < n; ++i) {
    double along = n == 3 ? (1 - i) * 0.4 : 0.36 * u(rng), cross = n == 3 ? 0.04 : 0.27 * u(rng);
    s.cams.push_back(make_synth_camera(true, along, cross, 0.01 * u(rng), 700e3, 700e3 / s.scene.params().gsd,
                                       Eigen::Vector3d(S / 2, S / 2, 0), size));
    ImageBias b;
    b.a = {5 * u(rng), 1e-4 * u(rng), 1e-4 * u(rng)};
    b.b = {5 * u(rng), 1e-4 * u(rng), 1e-4 * u(rng)};
    Eigen::Matrix2d IA;
    IA << 1 + b.a[1], b.a[2], b.b[1], 1 + b.b[2];
    const Eigen::Matrix2d inv = IA.inverse();
    const Eigen::Vector2d c(b.a[0], b.b[0]);
    RpcFitVolume v;
    Eigen::Vector3d sw = s.geo.to_llh({0, 0, 0}), ne = s.geo.to_llh({S, S, 0});
    v.lon0 = sw[0];
    v.lat0 = sw[1];
    v.lon1 = ne[0];
    v.lat1 = ne[1];
    v.h0 = 100 - 85;
    v.h1 = 100 + 85;
    const SynthCamera& cam = s.cams.back();
    AdjustImage im;
    im.path = "image" + std::to_string(i + 1);
    im.width = im.height = size;
    im.model = fit_rpc([&](const Eigen::Vector3d& g) { return Eigen::Vector2d(inv * (cam.project(s.geo.from_llh(g)) - c)); }, v).model;
    im.fixed = i == 0;
    s.images.push_back(im);
  }
}

std::vector<AdjustTrack> make_tracks(const Synthetic& s, long n, int min_views, int max_views, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, s.scene.scene_size());
  std::normal_distribution<double> noise(0, 0.1);
  std::uniform_int_distribution<int> nv(min_views, max_views);
  std::vector<AdjustTrack> out;
  std::vector<int> order(s.cams.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  for (long t = 0; t < n; ++t) {
    double X = u(rng), Y = u(rng);
    Eigen::Vector3d g(X, Y, s.scene.height(X, Y));
    AdjustTrack a;
    a.id = t + 1;
    std::shuffle(order.begin(), order.end(), rng);
    int k = std::min<int>(nv(rng), static_cast<int>(order.size()));
    std::vector<int> views(order.begin(), order.begin() + k);
    std::sort(views.begin(), views.end());
    for (int i : views) a.views.emplace_back(i, s.cams[i].project(g) + Eigen::Vector2d(noise(rng), noise(rng)));
    out.push_back(a);
  }
  return out;
}

void synthetic_case(const char* name, int images, long tracks, int min_views, int max_views, int threads) {
  std::mt19937_64 rng(42);
  Synthetic s;
  make_cameras(s, images, rng);
  auto t = make_tracks(s, tracks, min_views, max_views, rng);
  AdjustOptions o;
  o.threads = threads;
  o.progress = isatty(2);
  auto t0 = std::chrono::steady_clock::now();
  AdjustResult r = adjust_rpcs(s.images, t, o);
  report(name, s.images.size(), t.size(), r, seconds_since(t0));
}
}  // namespace

int main(int argc, char** argv) {
  const char* usage = "usage: bench_rpc_adjust [TRACKS IMAGE1 IMAGE2 ...]  (no arguments: the synthetic cases only)\n";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::fputs(usage, stdout);
      return 0;
    }
    if (a.size() > 1 && a[0] == '-') {
      std::fprintf(stderr, "bench_rpc_adjust: %s: no such option\n%s", a.c_str(), usage);
      return 2;
    }
  }
  if (argc == 2 || argc == 3) {  // tracks without two images: say so rather than run the synthetic cases alone
    std::fprintf(stderr, "bench_rpc_adjust: real tracks need the tracks file and two images or more\n%s", usage);
    return 2;
  }
  synthetic_case("synthetic triplet (1 thread)", 3, 7000, 3, 3, 1);
  if (argc >= 4) {
    std::vector<std::string> paths(argv + 2, argv + argc);
    std::vector<AdjustImage> images;
    for (const auto& p : paths) {
      AdjustImage im;
      im.path = p;
      ImageInfo info = image_info(p);
      im.width = info.width;
      im.height = info.height;
      im.model = load_image_rpc(p).model;
      images.push_back(im);
    }
    images[0].fixed = true;
    auto tracks = gather_tracks({argv[1]}, paths);
    AdjustOptions o;
    auto t0 = std::chrono::steady_clock::now();
    AdjustResult r = adjust_rpcs(images, tracks, o);
    report("real tracks (1 thread)", images.size(), tracks.size(), r, seconds_since(t0));
  }
  synthetic_case("50 images, 2..5 views (2 threads)", 50, 100000, 2, 5, 2);
  return 0;
}
