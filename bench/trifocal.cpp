// bench_trifocal: speed and accuracy of the trifocal methods (issue 4).
//
//   bench_trifocal [Google Benchmark options]
//       speed: every method at n = 1000 noise-free-plus-noise tracks; --ransac (ml) on 10 000 tracks
//       with 30% gross outliers. Goals: linear methods < 1 ms, ml < 20 ms, ransac < 100 ms.
//   bench_trifocal --accuracy [--trials N] [--sigma S] [--size PX]
//       the noise table: random satellite-like affine triplets (AffineScene, crops of PX pixels,
//       default 1000), Gaussian noise S px (default 0.5) per coordinate on n = 10, 100, 1000 fit tracks,
//       N trials (default 200; trial t uses scene seed t). For each method and n: the median over
//       trials of the reprojection RMSE on the fit tracks (reproj-eval's definition: root mean squared
//       2-D residual over tracks and views, and that / sqrt 2 per coordinate), the median transfer
//       RMSE (2-D, pixels) on 1000 noise-free check tracks against the truth, the ML bound
//       S sqrt((n - 4) / (2n)) per coordinate, and the ratio of the per-coordinate RMSE to the bound.
//       Then the robust figures: 1000 tracks, 30% gross outliers (one view of a track moved to a
//       random place in the image), --ransac 1.5: share of true inliers kept, and the RMSE on the true
//       inliers relative to the fit without outliers.
//   bench_trifocal --real TRACKS [--seed S] [--trials N]
//       the paper's table on real tracks: for n = 10, 100, 1000 (capped by the file) and every method,
//       N random subsets (default 20, seed S): fit on n tracks, RMSE on those fit tracks and on all the
//       other (held-out) tracks; medians over the subsets.
#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "tpkit/affine_camera.hpp"
#include "tpkit/formats.hpp"
#include "tpkit/reproj_eval.hpp"
#include "tpkit/trifocal_fit.hpp"
#include "tpkit/trifocal_transfer.hpp"

using namespace tpkit;

namespace {

struct Data {
  Eigen::MatrixXd fit, truth_fit, check;
};

Data make_data(std::uint64_t seed, int n, double sigma, double size, int n_check) {
  AffineSceneOptions o;
  o.seed = seed;
  o.image_size = size;
  const AffineScene s = AffineScene::random(o);
  Data d;
  d.truth_fit = s.project(s.points(n, seed * 1000 + 1));
  d.check = s.project(s.points(n_check, seed * 1000 + 2));
  std::mt19937_64 rng(seed * 1000 + 3);
  std::normal_distribution<double> N(0.0, sigma);
  d.fit = d.truth_fit;
  for (Eigen::Index r = 0; r < d.fit.rows(); ++r)
    for (int c = 0; c < 6; ++c) d.fit(r, c) += N(rng);
  return d;
}

// one view of `share` of the tracks moved to a uniformly random place of the image
std::vector<char> add_outliers(Eigen::MatrixXd& xy, double share, double size, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<char> outlier(xy.rows(), 0);
  for (Eigen::Index r = 0; r < xy.rows(); ++r)
    if (U(rng) < share) {
      outlier[r] = 1;
      int v = static_cast<int>(U(rng) * 3) % 3;
      double nx, ny;
      do {
        nx = U(rng) * size;
        ny = U(rng) * size;
      } while (std::hypot(nx - xy(r, 2 * v), ny - xy(r, 2 * v + 1)) < 20);  // gross: at least 20 px off
      xy(r, 2 * v) = nx;
      xy(r, 2 * v + 1) = ny;
    }
  return outlier;
}

double transfer_rmse(const TrifocalTensor& T, const Eigen::MatrixXd& check) {
  const Eigen::MatrixXd x3 = transfer_point_line_point(T, check.leftCols(4));
  return std::sqrt((x3 - check.rightCols(2)).rowwise().squaredNorm().mean());
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

double rmse_of(const TrifocalTensor& T, const Eigen::MatrixXd& fit, const Eigen::MatrixXd& eval) {
  return evaluate_reprojection(reprojection_frame(T, fit), eval).stats.rmse;
}

const char* arg_value(int argc, char** argv, const char* name) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], name) == 0) return argv[i + 1];
  return nullptr;
}
bool has_flag(int argc, char** argv, const char* name) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], name) == 0) return true;
  return false;
}

int accuracy(int argc, char** argv) {
  const int trials = arg_value(argc, argv, "--trials") ? std::atoi(arg_value(argc, argv, "--trials")) : 200;
  const double sigma = arg_value(argc, argv, "--sigma") ? std::atof(arg_value(argc, argv, "--sigma")) : 0.5;
  const double size = arg_value(argc, argv, "--size") ? std::atof(arg_value(argc, argv, "--size")) : 1000;
  std::printf("# noise table: sigma %.3g px per coordinate, %d trials, %g px images, 1000 noise-free check tracks\n",
              sigma, trials, size);
  std::printf("# rmse2d = sqrt(mean |r|^2 over tracks and views) on the fit tracks; rmse1d = rmse2d / sqrt 2;\n");
  std::printf("# bound = sigma sqrt((n-4)/(2n)) per coordinate; ratio = rmse1d / bound; transfer = 2-D RMSE of x3\n");
  std::printf("%-10s %5s %10s %10s %10s %8s %12s %6s\n", "method", "n", "rmse2d", "rmse1d", "bound", "ratio",
              "transfer", "fails");
  for (TrifocalMethod m : all_trifocal_methods()) {
    for (int n : {10, 100, 1000}) {
      std::vector<double> rm, tr;
      int fails = 0;
      for (int t = 1; t <= trials; ++t) {
        const Data d = make_data(static_cast<std::uint64_t>(t), n, sigma, size, 1000);
        try {
          const TrifocalTensor T = fit_trifocal(m, d.fit);
          rm.push_back(rmse_of(T, d.fit, d.fit));
          tr.push_back(transfer_rmse(T, d.check));
        } catch (const std::exception&) {
          ++fails;
        }
      }
      const double bound = sigma * std::sqrt((n - 4.0) / (2.0 * n));
      const double r2 = median(rm), r1 = r2 / std::sqrt(2.0);
      std::printf("%-10s %5d %10.4f %10.4f %10.4f %8.4f %12.4f %6d\n", trifocal_method_name(m).c_str(), n, r2, r1,
                  bound, r1 / bound, median(tr), fails);
      std::fflush(stdout);
    }
  }
  // robust figures
  const int rtrials = std::max(1, trials / 4);
  std::printf("# ransac: 1000 tracks, 30%% gross outliers, threshold 1.5 px, %d trials; kept = true inliers kept;\n",
              rtrials);
  std::printf("# rmse_ratio = RMSE on the true inliers (robust fit) / RMSE of the fit without outliers\n");
  std::printf("%-10s %10s %10s %12s %12s\n", "method", "kept_min", "kept_med", "ratio_med", "ratio_max");
  for (TrifocalMethod m : all_trifocal_methods()) {
    std::vector<double> kept, ratio;
    for (int t = 1; t <= rtrials; ++t) {
      Data d = make_data(static_cast<std::uint64_t>(t), 1000, sigma, size, 10);
      const Eigen::MatrixXd clean = d.fit;
      Eigen::MatrixXd dirty = d.fit;
      const std::vector<char> out = add_outliers(dirty, 0.3, size, 77 + t);
      RansacOptions ro;
      ro.threshold = 1.5;
      ro.seed = static_cast<std::uint64_t>(t);
      try {
        const RobustTrifocalFit rf = fit_trifocal_ransac(m, dirty, ro);
        long inl = 0, kept_n = 0;
        std::vector<Eigen::Index> idx;
        for (Eigen::Index r = 0; r < dirty.rows(); ++r)
          if (!out[r]) {
            ++inl;
            kept_n += rf.inlier[r] ? 1 : 0;
            idx.push_back(r);
          }
        Eigen::MatrixXd tin(idx.size(), 6);
        for (size_t q = 0; q < idx.size(); ++q) tin.row(q) = clean.row(idx[q]);
        const TrifocalTensor Tc = fit_trifocal(m, tin);
        kept.push_back(static_cast<double>(kept_n) / inl);
        ratio.push_back(rmse_of(rf.T, tin, tin) / rmse_of(Tc, tin, tin));
      } catch (const std::exception& e) {
        std::printf("# %s trial %d failed: %s\n", trifocal_method_name(m).c_str(), t, e.what());
      }
    }
    std::printf("%-10s %10.4f %10.4f %12.4f %12.4f\n", trifocal_method_name(m).c_str(),
                kept.empty() ? NAN : *std::min_element(kept.begin(), kept.end()), median(kept), median(ratio),
                ratio.empty() ? NAN : *std::max_element(ratio.begin(), ratio.end()));
    std::fflush(stdout);
  }
  return 0;
}

int real_table(int argc, char** argv) {
  const char* path = arg_value(argc, argv, "--real");
  const std::uint64_t seed = arg_value(argc, argv, "--seed") ? std::strtoull(arg_value(argc, argv, "--seed"), nullptr, 10) : 1;
  const int trials = arg_value(argc, argv, "--trials") ? std::atoi(arg_value(argc, argv, "--trials")) : 20;
  const Tracks tracks = read_tracks(path);
  if (tracks.views() != 3) {
    std::fprintf(stderr, "bench_trifocal: %s: needs three views\n", path);
    return 1;
  }
  const Eigen::Index N = tracks.xy.rows();
  std::printf("# real table: %s, %ld tracks, %d random subsets per cell (seed %llu); RMSE px as reproj-eval\n", path,
              static_cast<long>(N), trials, static_cast<unsigned long long>(seed));
  std::printf("# fit = RMSE on the n fit tracks; check = RMSE on all the other tracks (held out); medians\n");
  std::printf("%-10s %6s %10s %10s %6s\n", "method", "n", "fit", "check", "fails");
  for (TrifocalMethod m : all_trifocal_methods())
    for (int n0 : {10, 100, 1000}) {
      const Eigen::Index n = std::min<Eigen::Index>(n0, N - 1);
      std::vector<double> f, c;
      int fails = 0;
      for (int t = 0; t < trials; ++t) {
        std::mt19937_64 rng(seed * 100003 + 7919 * static_cast<std::uint64_t>(t) + static_cast<std::uint64_t>(n0));
        std::vector<Eigen::Index> perm(N);
        for (Eigen::Index q = 0; q < N; ++q) perm[q] = q;
        std::shuffle(perm.begin(), perm.end(), rng);
        Eigen::MatrixXd fit(n, 6), held(N - n, 6);
        for (Eigen::Index q = 0; q < N; ++q) (q < n ? fit.row(q) : held.row(q - n)) = tracks.xy.row(perm[q]);
        try {
          const TrifocalTensor T = fit_trifocal(m, fit);
          const ReprojectionFrame fr = reprojection_frame(T, fit);
          f.push_back(evaluate_reprojection(fr, fit).stats.rmse);
          c.push_back(evaluate_reprojection(fr, held).stats.rmse);
        } catch (const std::exception&) {
          ++fails;
        }
      }
      std::printf("%-10s %6ld %10.4f %10.4f %6d\n", trifocal_method_name(m).c_str(), static_cast<long>(n), median(f),
                  median(c), fails);
      std::fflush(stdout);
    }
  return 0;
}

// ---- speed --------------------------------------------------------------------------------------

void BM_Method(benchmark::State& state, TrifocalMethod m) {
  const Data d = make_data(1, static_cast<int>(state.range(0)), 0.5, 1000, 10);
  for (auto _ : state) {
    TrifocalTensor T = run_trifocal_method(m, d.fit);
    benchmark::DoNotOptimize(T);
  }
}
BENCHMARK_CAPTURE(BM_Method, dlt, TrifocalMethod::Dlt)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Method, affine_dlt, TrifocalMethod::AffineDlt)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Method, algebraic, TrifocalMethod::Algebraic)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Method, minimal, TrifocalMethod::Minimal)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Method, three_f, TrifocalMethod::ThreeF)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Method, ml, TrifocalMethod::Ml)->Arg(1000)->Unit(benchmark::kMillisecond);

void BM_FitChecked(benchmark::State& state, TrifocalMethod m) {
  const Data d = make_data(1, static_cast<int>(state.range(0)), 0.5, 1000, 10);
  for (auto _ : state) {
    TrifocalTensor T = fit_trifocal(m, d.fit);
    benchmark::DoNotOptimize(T);
  }
}
BENCHMARK_CAPTURE(BM_FitChecked, ml_with_input_checks, TrifocalMethod::Ml)->Arg(1000)->Unit(benchmark::kMillisecond);

void BM_Ransac(benchmark::State& state) {
  Data d = make_data(1, static_cast<int>(state.range(0)), 0.5, 1000, 10);
  add_outliers(d.fit, 0.3, 1000, 5);
  RansacOptions ro;
  ro.threshold = 1.5;
  size_t inl = 0;
  for (auto _ : state) {
    RobustTrifocalFit r = fit_trifocal_ransac(TrifocalMethod::Ml, d.fit, ro);
    inl = r.inliers;
    benchmark::DoNotOptimize(r);
  }
  state.counters["inliers"] = static_cast<double>(inl);
}
BENCHMARK(BM_Ransac)->Arg(10000)->Unit(benchmark::kMillisecond);

void BM_ReprojEval(benchmark::State& state) {
  const Data d = make_data(1, static_cast<int>(state.range(0)), 0.5, 1000, 10);
  const TrifocalTensor T = run_trifocal_method(TrifocalMethod::Ml, d.fit);
  for (auto _ : state) {
    auto r = evaluate_reprojection(reprojection_frame(T, d.fit), d.fit);
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_ReprojEval)->Arg(1000)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  if (has_flag(argc, argv, "--accuracy")) return accuracy(argc, argv);
  if (arg_value(argc, argv, "--real")) return real_table(argc, argv);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
