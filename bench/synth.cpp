// tp-synth benchmarks: the pieces of the renderer (albedo, terrain height + gradient, exact ray cast)
// and whole strips of a 1024-pixel view, single-threaded.
//   build*/bin/bench_synth [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

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
}  // namespace

BENCHMARK_MAIN();
