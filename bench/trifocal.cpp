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
//   bench_trifocal --coplanar [--trials N] [--sigma S] [--size PX] [--cross DEG] [--spread DEG]
//       single-pass geometry: random affine triplets whose viewing directions have one cross-track angle
//       DEG (default 0) give or take --spread DEG (default 0: the three directions coplanar); every
//       method at n = 100 and 1000 (N trials, default 100): median transfer RMSE on 1000 noise-free check
//       tracks and its ratio to ml's.
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

#include "tpkit/geometry/affine_camera.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/geometry/reproj_eval.hpp"
#include "tpkit/geometry/trifocal_fit.hpp"
#include "tpkit/geometry/trifocal_three_f.hpp"
#include "tpkit/geometry/trifocal_transfer.hpp"

using namespace tpkit;

namespace {

struct Data {
  Eigen::MatrixXd fit, truth_fit, check;
};

AffineScene single_pass_scene(std::uint64_t seed, double size, double cross, double spread) {
  AffineSceneOptions o;
  o.seed = seed;
  o.image_size = size;
  return AffineScene::single_pass(o, cross, spread);
}

Data make_data_in(const AffineScene& s, std::uint64_t seed, int n, double sigma, int n_check) {
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

Data make_data(std::uint64_t seed, int n, double sigma, double size, int n_check) {
  AffineSceneOptions o;
  o.seed = seed;
  o.image_size = size;
  return make_data_in(AffineScene::random(o), seed, n, sigma, n_check);
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

// Single-pass geometry: the methods on coplanar_scene triplets (cross-track angle --cross DEG, default
// 0, spread --spread DEG, default 0: coplanar directions), n = 100 and 1000, median transfer RMSE on
// 1000 noise-free check tracks and its ratio to ml's.
int coplanar_table(int argc, char** argv) {
  constexpr double kDeg = 3.14159265358979323846 / 180;
  const int trials = arg_value(argc, argv, "--trials") ? std::atoi(arg_value(argc, argv, "--trials")) : 100;
  const double sigma = arg_value(argc, argv, "--sigma") ? std::atof(arg_value(argc, argv, "--sigma")) : 0.5;
  const double size = arg_value(argc, argv, "--size") ? std::atof(arg_value(argc, argv, "--size")) : 1000;
  const double cross = arg_value(argc, argv, "--cross") ? std::atof(arg_value(argc, argv, "--cross")) : 0;
  const double spread = arg_value(argc, argv, "--spread") ? std::atof(arg_value(argc, argv, "--spread")) : 0;
  std::printf("# coplanar table: viewing directions with cross-track %g deg +- %g deg (0: coplanar), sigma %.3g px,"
              " %d trials, %g px images, 1000 noise-free check tracks\n", cross, spread, sigma, trials, size);
  std::printf("# transfer = median 2-D RMSE of x3 transferred from x1, x2 (px); ratio = transfer / ml's\n");
  std::printf("%-10s %5s %12s %8s %6s\n", "method", "n", "transfer", "ratio", "fails");
  const std::vector<int> ns = {100, 1000};
  std::vector<std::vector<double>> med(all_trifocal_methods().size(), std::vector<double>(ns.size(), NAN));
  for (size_t q = 0; q < ns.size(); ++q) {
    std::vector<std::vector<double>> tr(all_trifocal_methods().size());
    std::vector<int> fails(all_trifocal_methods().size(), 0);
    for (int t = 1; t <= trials; ++t) {
      const auto seed = static_cast<std::uint64_t>(t);
      const Data d = make_data_in(single_pass_scene(seed, size, cross * kDeg, spread * kDeg), seed, ns[q], sigma, 1000);
      for (size_t mi = 0; mi < all_trifocal_methods().size(); ++mi) try {
          tr[mi].push_back(transfer_rmse(fit_trifocal(all_trifocal_methods()[mi], d.fit), d.check));
        } catch (const std::exception&) {
          ++fails[mi];
        }
    }
    for (size_t mi = 0; mi < all_trifocal_methods().size(); ++mi) med[mi][q] = median(tr[mi]);
    const size_t ml_index = static_cast<size_t>(std::find(all_trifocal_methods().begin(), all_trifocal_methods().end(), TrifocalMethod::Ml) - all_trifocal_methods().begin());
    const double ml = med[ml_index][q];
    for (size_t mi = 0; mi < all_trifocal_methods().size(); ++mi)
      std::printf("%-10s %5d %12.4f %8.3f %6d\n", trifocal_method_name(all_trifocal_methods()[mi]).c_str(), ns[q],
                  med[mi][q], med[mi][q] / ml, fails[mi]);
    std::fflush(stdout);
  }
  // three-f against ml by the epipolar angle of the adjusted F (trifocal_three_f.hpp), trial by trial,
  // over a spread of geometries: what kThreeFMinAngleDeg refuses and what it keeps
  std::printf("# three-f / ml transfer ratio by the epipolar angle (deg) of three-f's adjusted F, cross-track %g deg\n"
              "# +- 0 .. 10 deg spread, %d trials per spread and n\n", cross, trials);
  std::printf("%5s %14s %7s %14s %14s\n", "n", "angle", "trials", "median ratio", "90% ratio");
  const double edges[] = {0, 0.1, 0.3, 0.5, 1, 3, 90};
  for (int n : ns) {
    std::vector<std::vector<double>> bins(6);
    for (double sp : {0.0, 0.3, 1.0, 3.0, 10.0})
      for (int t = 1; t <= trials; ++t) {
        const auto seed = static_cast<std::uint64_t>(t);
        const Data d = make_data_in(single_pass_scene(seed, size, cross * kDeg, sp * kDeg), seed, n, sigma, 1000);
        try {
          ThreeFReport rep;
          const double r3 = transfer_rmse(trifocal_three_f(d.fit, 0, &rep), d.check);
          const double rm = transfer_rmse(fit_trifocal(TrifocalMethod::Ml, d.fit), d.check);
          for (int b = 0; b < 6; ++b)
            if (rep.epipolar_angle_deg >= edges[b] && rep.epipolar_angle_deg < edges[b + 1]) bins[b].push_back(r3 / rm);
        } catch (const std::exception&) {
        }
      }
    for (int b = 0; b < 6; ++b) {
      std::vector<double> v = bins[b];
      std::sort(v.begin(), v.end());
      const double p90 = v.empty() ? NAN : v[static_cast<size_t>(0.9 * (v.size() - 1))];
      std::printf("%5d %6.1f .. %-5.1f %7zu %14.3f %14.3f\n", n, edges[b], edges[b + 1], v.size(), median(v), p90);
    }
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
  if (has_flag(argc, argv, "--coplanar")) return coplanar_table(argc, argv);
  if (arg_value(argc, argv, "--real")) return real_table(argc, argv);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
