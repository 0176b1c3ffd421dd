// tp-synth benchmarks: the pieces of the renderer (albedo, terrain height + gradient, exact ray cast)
// and whole strips of a 1024-pixel view, single-threaded.
//   build*/bin/bench_synth [--benchmark_filter=...]
//   build*/bin/bench_synth --agreement [SIZE [ROWS]]
//       The fast renderer (SynthScene::render_rows) against the exact per-sample reference
//       (synth_reference_rows) on ROWS rows (default 64) in the middle of each view of the default scene
//       of SIZE pixels (default 1024), noise 0, at --supersample 4 and 8 (and the reference 4 vs 8): RMS and
//       largest DN difference, and the CPU time of each, ms per megapixel per view, single-threaded.
//   build*/bin/bench_synth --compare A.tif B.tif
//       RMS, mean and largest DN difference of two images of the same size (e.g. two tp-synth versions).
#include <benchmark/benchmark.h>

#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "tpkit/core/image_io.hpp"
#include "tpkit/synth/synth_render.hpp"
#include "tpkit/synth/synth_scene.hpp"

namespace {
const tpkit::SynthScene& scene(const std::string& camera) {
  static tpkit::SynthScene affine([] {
    tpkit::SynthParams p;
    return p;
  }());
  static tpkit::SynthScene perspective([] {
    tpkit::SynthParams p;
    p.camera = "perspective";
    return p;
  }());
  return camera == "affine" ? affine : perspective;
}

// 1024 random ground positions (x, y interleaved) over the scene, fixed seed.
std::vector<double> ground_samples(const tpkit::SynthScene& s) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, s.scene_size());
  std::vector<double> xy(2048);
  for (auto& v : xy) v = u(rng);
  return xy;
}

void BM_Albedo(benchmark::State& st) {
  const auto& s = scene("affine");
  const std::vector<double> xy = ground_samples(s);
  size_t i = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(s.albedo(xy[i], xy[i + 1]));
    i = (i + 2) & 2047;
  }
}
BENCHMARK(BM_Albedo);

void BM_HeightGradient(benchmark::State& st) {
  const auto& s = scene("affine");
  const std::vector<double> xy = ground_samples(s);
  size_t i = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(s.height_gradient(xy[i], xy[i + 1]));
    i = (i + 2) & 2047;
  }
}
BENCHMARK(BM_HeightGradient);

// Exact first intersection of a pixel's ray (view 0 = forward, 22 deg).
void BM_GroundPoint(benchmark::State& st) {
  const auto& s = scene(st.range(0) ? "perspective" : "affine");
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, s.params().size - 1);
  std::vector<double> xy(2048);
  for (auto& v : xy) v = u(rng);
  size_t i = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(s.ground_point(0, xy[i], xy[i + 1]));
    i = (i + 2) & 2047;
  }
}
BENCHMARK(BM_GroundPoint)->Arg(0)->Arg(1);

// 32 rows of 1024 pixels of view `range(0)`, default parameters (4 x 4 supersampling).
void BM_RenderStrip(benchmark::State& st) {
  const auto& s = scene("affine");
  std::vector<uint16_t> out(32 * 1024);
  for (auto _ : st) {
    s.render_rows(static_cast<int>(st.range(0)), 496, 32, out.data());
    benchmark::DoNotOptimize(out.data());
  }
  st.counters["px/s"] = benchmark::Counter(32.0 * 1024 * st.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderStrip)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

struct Diff {
  double rms = 0, mean = 0, max = 0;
};
template <class A, class B>
Diff diff(const A& a, const B& b, size_t n) {
  Diff d;
  double ss = 0, s = 0;
  for (size_t i = 0; i < n; ++i) {
    const double e = static_cast<double>(a[i]) - static_cast<double>(b[i]);
    ss += e * e;
    s += e;
    d.max = std::max(d.max, std::abs(e));
  }
  d.rms = std::sqrt(ss / static_cast<double>(n));
  d.mean = s / static_cast<double>(n);
  return d;
}

int compare(const std::string& a, const std::string& b) {
  const tpkit::Raster ra = tpkit::read_band(a), rb = tpkit::read_band(b);
  if (ra.width != rb.width || ra.height != rb.height) {
    std::fprintf(stderr, "bench_synth: %s and %s differ in size\n", a.c_str(), b.c_str());
    return 1;
  }
  const Diff d = diff(ra.data, rb.data, ra.data.size());
  std::printf("%s - %s: rms %.3f DN, mean %.3f DN, max %.0f DN over %zu pixels\n", a.c_str(), b.c_str(), d.rms, d.mean, d.max,
              ra.data.size());
  return 0;
}

int agreement(long size, long rows) {
  // CPU time of this (single) thread, so that other jobs on the machine do not count
  struct clock {
    static std::clock_t now() { return std::clock(); }
  };
  auto ms = [](std::clock_t t0) { return 1000.0 * static_cast<double>(std::clock() - t0) / CLOCKS_PER_SEC; };
  std::printf("default scene, size %ld, noise 0, rows %ld..%ld of each view, single-threaded\n", size, size / 2 - rows / 2,
              size / 2 - rows / 2 + rows - 1);
  std::vector<std::vector<uint16_t>> ref4;
  for (int n : {4, 8}) {
    tpkit::SynthParams p;
    p.size = size;
    p.noise = 0;
    p.supersample = n;
    const tpkit::SynthScene s(p);
    const long y0 = size / 2 - rows / 2, np = rows * size;
    double t_fast = 0, t_ref = 0, ss = 0, worst = 0, ss48 = 0;
    for (int v = 0; v < s.views(); ++v) {
      std::vector<uint16_t> fast(static_cast<size_t>(np)), ref(static_cast<size_t>(np));
      auto t0 = clock::now();
      s.render_rows(v, y0, rows, fast.data());
      t_fast += ms(t0);
      t0 = clock::now();
      tpkit::synth_reference_rows(s, v, y0, rows, ref.data());
      t_ref += ms(t0);
      const Diff d = diff(fast, ref, static_cast<size_t>(np));
      ss += d.rms * d.rms;
      worst = std::max(worst, d.max);
      if (n == 4) ref4.push_back(ref);
      else {
        const Diff d48 = diff(ref4[static_cast<size_t>(v)], ref, static_cast<size_t>(np));
        ss48 += d48.rms * d48.rms;
      }
    }
    const double mp = static_cast<double>(np) * s.views() / 1e6;
    std::printf("supersample %d: fast - reference rms %.3f DN, max %.0f DN; fast %.0f ms/MP/view, reference %.0f ms/MP/view (x%.1f)\n",
                n, std::sqrt(ss / s.views()), worst, t_fast / mp, t_ref / mp, t_ref / t_fast);
    if (n == 8) std::printf("reference 4x4 - reference 8x8 rms %.3f DN\n", std::sqrt(ss48 / s.views()));
  }
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "--compare") == 0) {
    if (argc != 4) {
      std::fprintf(stderr, "usage: bench_synth --compare A.tif B.tif\n");
      return 2;
    }
    return compare(argv[2], argv[3]);
  }
  if (argc >= 2 && std::strcmp(argv[1], "--agreement") == 0)
    return agreement(argc > 2 ? std::atol(argv[2]) : 1024, argc > 3 ? std::atol(argv[3]) : 64);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
