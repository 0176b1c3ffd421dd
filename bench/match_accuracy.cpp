// bench_match_accuracy: accuracy of tp-match / tp-chain tie points.
//
//   bench_match_accuracy --synth DIR [--check MED P90] [--threads N] [--window W]
//       DIR from `tp-synth --out DIR`: matches view1-view2, view1-view3, view2-view3 with the tp-match
//       library (default options), chains them into triplets, and prints for each pair and for the
//       triplets the error distribution (count, median, 90th percentile, max; pixels) of raw SIFT
//       and of the refined positions in image 2 (resp. views 2 and 3) against the truth:
//       X = ground_point(view 1, x1, y1), truth = project(view v, X) when visible; then the triplets'
//       consistency with the true cameras (residuals of views 2 and 3 at the best 3-D point).
//       --check: exit status 1 when the triplets' median or 90th percentile (views 2 and 3 together)
//       is above MED / P90.
//       --score FILE A B: instead, score any program's matches file of views A and B (1-based; e.g. COLMAP's
//       through tp-convert --from colmap) against the truth: matches, correct (< 1 px), error median/p90.
//       --min-corr R, --max-sigma PX: the LSM acceptance (tp-match's options); --size-recheck Q, --edge-share S: tp-match's; --contrast C: the SIFT
//       contrast threshold (tp-match --contrast); --nodata V: grey level of
//       invalid pixels (tp-synth --nodata-band writes 0).
//       --sigma-deciles: also print, over the refined matches of the three pairs, the RMS error (per
//       coordinate, sqrt(mean(ex^2 + ey^2) / 2)) against the RMS sigma in each decile of sigma, and their ratio
//       (issue 52: within [0.7, 1.4] when the sigma predicts the error), and the same over the matches
//       whose error is below 1 px (a wrong match is an outlier, not an imprecise position: no sigma predicts it);
//       with --multi also over the non-template views the multi-image LSM refined. --sigma-scale K, --sigma-floor F:
//       the calibration of the sigma (LsmOptions; 1 and 0 print the normal equations' own);
//       --mask K: the residual mask (LsmOptions::mask_k, 0 = off); --mask-fit K: the fit's own (mask_fit_k, 0 = off).
//       --dump FILE: one row per refined match with truth: pair, x1 y1, refined and raw error (x, y), and
//       the true local map's Jacobian and Hessians (central differences, 1 px) for error analysis.
//       --multi: then the triplets refined by multi-image LSM (tp-refine's library: multi_image_lsm.hpp,
//       RPCs from DIR, biases estimated from the triplets) and their error against the truth before ->
//       after: views 2+3 with the truth under view 1's position, and every non-template view with the
//       truth under the template's position (the refinement keeps the template fixed), sigma ratio.
//       --multi-template1: view 1 is always the template; --model-sigma PX, --no-curvature, --multi-highpass
//       auto|SIGMA (default auto) as tp-refine's.
//   bench_match_accuracy --tracks FILE [--check-rmse R]
//       Affine maximum-likelihood fit of the tracks (Tomasi-Kanade: rank-3 factorization of the
//       centred 2K x n measurement matrix) and its reprojection RMSE, sqrt(mean squared 2-D residual)
//       over all views and tracks, pixels. --check-rmse: exit 1 when above R.
//   bench_match_accuracy --render8 IN OUT
//       The 8-bit rendering tp-match's detector sees (percentile stretch 0.5..99.5 of band 1).
//
// Scenes with buildings and trees (tp-synth --scene buildings): the truth is the first surface on view 1's
// ray (ground, roof, wall or crown); a match whose point is hidden in the other view (behind a wall or a
// crown) or outside it is counted on its own line, not as an error; the triplets' views 2+3 errors are
// also split by the surface under view 1's point and by whether a wall, roof or crown edge lies within 5 px.
// Figures (2-core machine, 2026-12-07, the pairwise product: tp-match defaults, tp-chain), triplets' views
// 2+3 against the truth:
//   tp-synth --out def --threads 2; bench_match_accuracy --synth def --threads 2
//     (default scene, 1024 px, relief 150 m): 4922 triplets, median 0.0667, p90 0.1829, max 10.65 px;
//     refined pair 1-3: median 0.0827, p90 0.2088 px.
//   tp-synth --out town --scene buildings --threads 2; bench_match_accuracy --synth town --threads 2
//     (the same terrain with 428 buildings and 452 trees): 3238 triplets, median 0.0472, p90 0.1802,
//     max 18.30 px (ground 0.0731 / 0.2088, roofs 0.0198 / 0.0810, crowns 4 triplets all wrong, within
//     5 px of an edge 0.0606 / 0.2855 against 0.0457 / 0.1748 away from edges); refined pair 1-3: median
//     0.0511, p90 0.1964 px; hidden in the other view: 14, 6 and 22 matches of pairs 1-2, 1-3, 2-3.
//   tp-synth --out town2 --scene buildings --second-date 0.5 --threads 2 (views 2 and 3 a second date: the
//     second sun moves the shadows): 1258 triplets, median 0.0367, p90 0.1746, max 96.5 px (ground 0.1482 /
//     0.4478 over 368, roofs 0.0309 / 0.0996 over 2148: across dates the ground, retextured and reshadowed,
//     is mostly lost and what is kept is worse).
#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "tpkit/core/formats.hpp"
#include "tpkit/match/image_tiles.hpp"
#include "tpkit/match/match_pair.hpp"
#include "tpkit/match/multi_image_lsm.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/synth/synth_scene.hpp"
#include "tpkit/synth/synth_structures.hpp"
#include "tpkit/match/tracks_chain.hpp"

namespace {
struct Dist {
  long n = 0;
  double med = 0, p90 = 0, max = 0;
};
Dist dist(std::vector<double> e) {
  Dist d;
  d.n = static_cast<long>(e.size());
  if (e.empty()) return d;
  std::sort(e.begin(), e.end());
  auto q = [&](double p) { return e[std::min(e.size() - 1, static_cast<size_t>(std::floor(p * (e.size() - 1) + 0.5)))]; };
  d.med = q(0.5);
  d.p90 = q(0.9);
  d.max = e.back();
  return d;
}
void print(const char* what, const Dist& d) {
  std::printf("  %-26s count %6ld  median %.4f  p90 %.4f  max %.4f px\n", what, d.n, d.med, d.p90, d.max);
}

// Affine ML fit of tracks: RMSE of the 2-D residuals, pixels.
double affine_ml_rmse(const tpkit::Tracks& t, std::vector<double>* per_track = nullptr) {
  const int K = t.views();
  const Eigen::Index n = static_cast<Eigen::Index>(t.size());
  Eigen::MatrixXd W(2 * K, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int c = 0; c < 2 * K; ++c) W(c, i) = t.xy(i, c);
  Eigen::VectorXd mean = W.rowwise().mean();
  W.colwise() -= mean;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(W * W.transpose());
  Eigen::MatrixXd U = es.eigenvectors().rightCols(3);  // the three largest
  Eigen::MatrixXd R = W - U * (U.transpose() * W);
  if (per_track) {
    per_track->resize(n);
    for (Eigen::Index i = 0; i < n; ++i) (*per_track)[i] = std::sqrt(R.col(i).squaredNorm() / K);
  }
  return std::sqrt(R.squaredNorm() / (static_cast<double>(K) * n));
}

// Truth of a pixel of a view: the first intersection of its viewing ray with the surface (terrain, and
// the roofs, walls and crowns of a scene with structures).
std::optional<Eigen::Vector3d> ground_of(const tpkit::SynthScene& s, int view, double x, double y) {
  return s.ground_point(view, x, y);
}

// --- scenes with buildings and trees (tp-synth --scene buildings): occluded truth ---
// Whether view `v` sees ground point X: seen, outside its image, or hidden (by a wall, a crown or the
// terrain). A match whose ground point is hidden in the other view has no true position there: it is
// counted as such (Hidden::print), not as an error.
enum class Seen { yes, outside, hidden };
Seen seen_in(const tpkit::SynthScene& s, int v, const Eigen::Vector3d& X) {
  if (s.visible(v, X)) return Seen::yes;
  const Eigen::Vector2d x = s.project(v, X);
  const double n = static_cast<double>(s.params().size);
  return x.x() >= 0 && x.y() >= 0 && x.x() <= n - 1 && x.y() <= n - 1 ? Seen::hidden : Seen::outside;
}
struct Hidden {
  long hidden = 0, outside = 0;
  void add(Seen k) { (k == Seen::hidden ? hidden : outside) += k != Seen::yes; }
  void print(const char* what) const {
    if (hidden || outside)
      std::printf("  %-26s hidden %ld, outside the image %ld (no true position: not counted as errors)\n", what, hidden, outside);
  }
};
// Where a view-1 point lies in a scene with structures: on the ground, a roof, a wall or a crown, and
// whether its neighbourhood (8 points 5 px around it in view 1) crosses onto another surface (a wall, roof
// or crown edge, an occlusion edge: the map between the views is not affine there).
int surface_class(const tpkit::SynthScene& s, double x, double y, bool* edge) {
  const auto c = s.surface(0, x, y);
  *edge = false;
  if (!c) return 0;
  for (int k = 0; k < 8 && !*edge; ++k) {
    const double a = k * 0.785398163397448;
    const auto q = s.surface(0, x + 5 * std::cos(a), y + 5 * std::sin(a));
    *edge = !q || q->kind != c->kind || q->id != c->id;
  }
  return c->kind;
}
void print_scene(const tpkit::SynthScene& s) {
  const tpkit::SynthParams& p = s.params();
  if (!s.has_structures()) return;
  std::printf("scene: buildings %g, trees %g (%ld buildings, %ld trees)\n", p.buildings, p.trees, s.structures().buildings(),
              s.structures().trees());
}

double secs(std::chrono::steady_clock::time_point a) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
}

// Deciles of sigma: RMS error per coordinate against RMS sigma in each (sig_err: sigma and squared error
// per coordinate, (ex^2 + ey^2) / 2), and the same over the errors below 1 px.
void print_sigma_deciles(std::vector<std::pair<double, double>> sig_err, const char* what) {
  if (sig_err.size() < 10) return;
  std::sort(sig_err.begin(), sig_err.end());
  const size_t N = sig_err.size();
  std::printf("sigma deciles (%zu %s; error per coordinate against the truth):\n", N, what);
  double worst_lo = 1e9, worst_hi = 0;
  for (int d = 0; d < 10; ++d) {
    const size_t a = d * N / 10, b = (d + 1) * N / 10;
    double ss = 0, se = 0, ssc = 0, sec = 0;
    long wrong = 0;
    for (size_t q = a; q < b; ++q) {
      ss += sig_err[q].first * sig_err[q].first, se += sig_err[q].second;
      if (sig_err[q].second < 0.5) ssc += sig_err[q].first * sig_err[q].first, sec += sig_err[q].second;  // error < 1 px
      else ++wrong;
    }
    const double rs = std::sqrt(ss / (b - a)), re = std::sqrt(se / (b - a)), ratio = re / rs;
    const double ratio_c = std::sqrt(sec / ssc);
    worst_lo = std::min(worst_lo, ratio), worst_hi = std::max(worst_hi, ratio);
    std::printf("  decile %2d  sigma %.4f..%.4f  rms sigma %.4f  rms error %.4f  ratio %.3f  (errors < 1 px: ratio %.3f, %ld wrong)\n",
                d + 1, sig_err[a].first, sig_err[b - 1].first, rs, re, ratio, ratio_c, wrong);
  }
  std::printf("  error / sigma ratio over the deciles: %.3f..%.3f\n", worst_lo, worst_hi);
}

// The triplets refined by multi-image LSM, their errors against the truth before and after (the same
// tracks: those the refinement kept).
void multi_image(const tpkit::SynthScene& scene, const std::string* v, const tpkit::ImageSource* src, const tpkit::Tracks& t,
                 int threads, bool template1, double model_sigma, bool no_curvature, double highpass, double taper, bool deciles) {
  std::vector<tpkit::RpcModel> models(3);
  std::vector<tpkit::Raster> rasters(3);
  std::vector<const tpkit::RpcModel*> mp;
  for (int k = 0; k < 3; ++k) {
    models[k] = tpkit::load_image_rpc(v[k]).model;
    rasters[k] = tpkit::read_valid_region(src[k], 0, 0, src[k].info.width, src[k].info.height);
    mp.push_back(&models[k]);
  }
  std::vector<double> brms;
  const auto bias = tpkit::estimate_track_biases(t, mp, tpkit::BiasModel::affine, 0, 4, &brms);
  std::vector<tpkit::MultiLsmImage> images(3);
  for (int k = 0; k < 3; ++k) images[k] = {&rasters[k], &models[k], bias[k], brms[k] / std::sqrt(2.0)};
  tpkit::MultiLsmOptions o;
  if (template1) o.template_image = 0;
  if (model_sigma >= 0) o.model_sigma = model_sigma;
  o.curvature = !no_curvature;
  auto t0 = std::chrono::steady_clock::now();
  // tp-refine's high-pass: chosen on a sample of the tracks (highpass < 0) or as given
  tpkit::HighpassChoice hc;
  if (highpass >= 0) hc.sigma = highpass;
  else hc = tpkit::choose_track_highpass(t, images, o, threads);
  for (auto& ras : rasters) tpkit::highpass_raster(ras, hc.sigma);
  std::printf("multi-image LSM highpass: %s\n", tpkit::describe_track_highpass(hc, highpass >= 0).c_str());
  // tp-refine's window size: chosen on a sample of the tracks, or given (that size alone)
  if (taper >= 0) {
    o.taper = taper, o.window = std::max(21, 2 * static_cast<int>(std::round(2.75 * taper)) + 1), o.fallback_window = 0;
    std::printf("multi-image LSM size: taper %g px, window %d px (--multi-taper)\n", o.taper, o.window);
  } else {
    const tpkit::WindowSizeChoice size = tpkit::choose_track_size(t, images, o, threads);
    tpkit::use_track_size(size, o);
    std::printf("multi-image LSM size: %s\n", tpkit::describe_window_size(size, false, "", "sampled tracks").c_str());
  }
  tpkit::MultiLsmStats st;
  const tpkit::Tracks r = tpkit::refine_tracks(t, images, o, threads, &st);
  const double dt = secs(t0);
  std::printf("multi-image LSM (model sigma %.3g px (negative: each view's bias fit), %s, template %s): %ld triplets -> %ld tracks (%ld dropped), views dropped %ld, %.2f s\n",
              o.model_sigma, o.curvature ? "curvature" : "planar", template1 ? "view 1" : "chosen", st.tracks, st.tracks_written,
              st.tracks_dropped, st.views_dropped, dt);
  std::printf("  bias fit residual RMS: view 1 (offsets) %.4f, view 2 %.4f, view 3 %.4f px; templates per view %ld %ld %ld; dropped:", brms[0], brms[1], brms[2],
              st.template_count[0], st.template_count[1], st.template_count[2]);
  for (int i = 0; i < tpkit::kMultiLsmStatusCount; ++i)
    if (st.by_status[i]) std::printf(" %s %ld", tpkit::to_string(static_cast<tpkit::MultiLsmViewStatus>(i)), st.by_status[i]);
  std::printf("\n");
  std::map<long long, size_t> row_of;
  for (size_t i = 0; i < t.size(); ++i) row_of[t.id[i]] = i;
  const int ct = r.extra.find("template");
  std::vector<double> b23, a23, bnt, ant, sig, err2;
  std::vector<std::pair<double, double>> sig_err;  // every non-template view: sigma, squared error per coordinate
  for (size_t i = 0; i < r.size(); ++i) {
    const size_t j = row_of.at(r.id[i]);
    const int tv = static_cast<int>(r.extra.values(i, ct)) - 1;
    // truth under view 1 (its position is the same before and after only when it is the template)
    if (auto X = ground_of(scene, 0, r.xy(i, 0), r.xy(i, 1)))
      for (int k = 1; k < 3; ++k)
        if (r.seen(i, k) && scene.visible(k, *X)) {
          const Eigen::Vector2d tr = scene.project(k, *X);
          a23.push_back((r.point(i, k) - tr).norm());
        }
    if (auto X = ground_of(scene, 0, t.xy(j, 0), t.xy(j, 1)))
      for (int k = 1; k < 3; ++k)
        if (r.seen(i, k) && scene.visible(k, *X)) b23.push_back((t.point(j, k) - scene.project(k, *X)).norm());
    // truth under the template
    if (auto X = ground_of(scene, tv, r.xy(i, 2 * tv), r.xy(i, 2 * tv + 1)))
      for (int k = 0; k < 3; ++k) {
        if (k == tv || !r.seen(i, k) || !scene.visible(k, *X)) continue;
        const Eigen::Vector2d tr = scene.project(k, *X);
        ant.push_back((r.point(i, k) - tr).norm());
        bnt.push_back((t.point(j, k) - tr).norm());
        const double s = r.extra.values(i, r.extra.find("sigma" + std::to_string(k + 1)));
        if (ant.back() < 1) sig.push_back(s * s), err2.push_back(ant.back() * ant.back() / 2);
        sig_err.push_back({s, ant.back() * ant.back() / 2});
      }
  }
  print("before, views 2+3", dist(b23));
  print("after, views 2+3", dist(a23));
  print("before, non-template views", dist(bnt));
  print("after, non-template views", dist(ant));
  double ss = 0, se = 0;
  for (size_t i = 0; i < sig.size(); ++i) ss += sig[i], se += err2[i];
  if (!sig.empty())
    std::printf("  RMS error per coordinate / RMS sigma (errors < 1 px) %.3f (RMS sigma %.4f px)\n", std::sqrt(se / ss),
                std::sqrt(ss / sig.size()));
  if (deciles) print_sigma_deciles(sig_err, "non-template views refined by multi-image LSM");
}
}  // namespace

int main(int argc, char** argv) {
  try {
    std::string synth, tracks, r_in, r_out;
    double cmed = -1, cp90 = -1, crmse = -1;
    int threads = std::max(1u, std::thread::hardware_concurrency());
    int window = 21;
    double taper = 3;
    bool l2 = false, global = false, no_retry = false;
    bool size_given = false;  // --window / --taper: that size (tp-match's choice off)
    std::string dump;
    int quad = -1;
    double cut = -1, tol = -1, tmin = -1, tmax = -1, cref = -1;
    int adaptive = -1, sit = -1, epic = -1;
    double stol = -1, min_corr = -2, max_sigma = -1, contrast = -1, recheck = -1, edge_share = -1;
    double sigma_scale = -1, sigma_floor = -1, mask_k = -1;
    bool deciles = false;
    double mask_fit = -1;
    int sandwich = -1;
    std::optional<double> nodata;
    std::string score;
    bool multi = false, multi_t1 = false, no_curv = false;
    double model_sigma = -1, multi_highpass = -1;  // multi_highpass < 0: auto
    double multi_taper = -1;  // < 0: auto (tp-refine's choice); else that taper alone (3: window 21, 5: 29)
    int score_a = 1, score_b = 2;
    const char* usage =
        "usage: bench_match_accuracy --synth DIR [--check MED P90] [--no-retry] [--multi | --multi-template1 [--model-sigma PX] [--no-curvature] [--multi-highpass auto|SIGMA] [--multi-taper auto|3|5]] | --tracks FILE [--check-rmse R] | --render8 IN OUT\n";
    for (int i = 1; i < argc; ++i) {
      std::string a = argv[i];
      auto need = [&](int k) {
        if (i + k >= argc) throw std::runtime_error("missing value after " + a);
      };
      // the next argument as a number of option `a` (std::stod alone would say only "stod")
      auto num = [&]() {
        const std::string v = argv[++i];
        char* end = nullptr;
        const double d = std::strtod(v.c_str(), &end);
        if (v.empty() || *end != '\0' || !std::isfinite(d)) throw std::runtime_error(a + ": not a number: '" + v + "'");
        return d;
      };
      auto whole = [&]() {
        const double d = num();
        if (d != std::floor(d) || std::fabs(d) > 1e9) throw std::runtime_error(a + ": not a whole number: '" + argv[i] + "'");
        return static_cast<int>(d);
      };
      if (a == "--synth") need(1), synth = argv[++i];
      else if (a == "--tracks") need(1), tracks = argv[++i];
      else if (a == "--check") need(2), cmed = num(), cp90 = num();
      else if (a == "--check-rmse") need(1), crmse = num();
      else if (a == "--threads") need(1), threads = whole();
      else if (a == "--window") need(1), window = whole(), size_given = true;
      else if (a == "--taper") need(1), taper = num(), size_given = true;
      else if (a == "--l2") l2 = true;
      else if (a == "--global") global = true;
      else if (a == "--no-retry") no_retry = true;
      else if (a == "--dump") need(1), dump = argv[++i];
      else if (a == "--quadratic") need(1), quad = whole();
      else if (a == "--epipolar-curvature") need(1), epic = whole();
      else if (a == "--support") need(1), cut = num();
      else if (a == "--adaptive") need(1), adaptive = whole();
      else if (a == "--taper-min") need(1), tmin = num();
      else if (a == "--taper-max") need(1), tmax = num();
      else if (a == "--curvature-ref") need(1), cref = num();
      else if (a == "--tolerance") need(1), tol = num();
      else if (a == "--stage-tolerance") need(1), stol = num();
      else if (a == "--stage-iterations") need(1), sit = whole();
      else if (a == "--render8") need(2), r_in = argv[++i], r_out = argv[++i];
      else if (a == "--min-corr") need(1), min_corr = num();
      else if (a == "--max-sigma") need(1), max_sigma = num();
      else if (a == "--size-recheck") need(1), recheck = num();
      else if (a == "--edge-share") need(1), edge_share = num();
      else if (a == "--contrast") need(1), contrast = num();
      else if (a == "--sigma-deciles") deciles = true;
      else if (a == "--sigma-scale") need(1), sigma_scale = num();
      else if (a == "--sigma-floor") need(1), sigma_floor = num();
      else if (a == "--mask") need(1), mask_k = num();
      else if (a == "--mask-fit") need(1), mask_fit = num();
      else if (a == "--sigma-sandwich") need(1), sandwich = whole();
      else if (a == "--nodata") need(1), nodata = num();
      else if (a == "--multi") multi = true;
      else if (a == "--multi-template1") multi = multi_t1 = true;
      else if (a == "--model-sigma") need(1), model_sigma = num();
      else if (a == "--no-curvature") no_curv = true;
      else if (a == "--multi-highpass") need(1), multi_highpass = std::string(argv[i + 1]) == "auto" ? (++i, -1.0) : num();
      else if (a == "--multi-taper") need(1), multi_taper = std::string(argv[i + 1]) == "auto" ? (++i, -1.0) : num();
      else if (a == "--score") need(3), score = argv[++i], score_a = whole(), score_b = whole();
      else {
        std::fputs(usage, a == "--help" || a == "-h" ? stdout : stderr);
        return a == "--help" || a == "-h" ? 0 : 2;
      }
    }
    if (!r_in.empty()) {
      auto s = tpkit::open_image_source(r_in, 0, {}, "");
      auto st = tpkit::percentile_stretch(s);
      auto r = tpkit::read_valid_region(s, 0, 0, s.info.width, s.info.height);
      tpkit::write_image_u8(r_out, r.width, r.height, tpkit::render_u8(r, st));
      std::fprintf(stderr, "%s: stretch %g..%g -> %s\n", r_in.c_str(), st.lo, st.hi, r_out.c_str());
      return 0;
    }
    bool fail = false;
    if (!tracks.empty()) {
      tpkit::Tracks t = tpkit::read_tracks(tracks);
      std::vector<double> e;
      double rmse = affine_ml_rmse(t, &e);
      Dist d = dist(e);
      long over = std::count_if(e.begin(), e.end(), [](double v) { return v > 1.0; });
      std::printf("%s: %zu tracks, %d views; affine ML (rank-3 factorization) reprojection RMSE %.4f px\n", tracks.c_str(),
                  t.size(), t.views(), rmse);
      print("per-track rms residual", d);
      std::printf("  tracks with rms residual > 1 px: %ld\n", over);
      if (crmse > 0 && !(rmse <= crmse)) {
        std::printf("FAIL: RMSE %.4f > %.4f\n", rmse, crmse);
        fail = true;
      }
    }
    if (!synth.empty() && !score.empty()) {
      // any program's matches (x1 y1 in view A, x2 y2 in view B) against the truth: the error of (x2, y2)
      // from the projection in B of the ground point of (x1, y1) in A; correct = error below 1 px
      tpkit::SynthScene scene = tpkit::SynthScene::load(synth);
      const tpkit::Matches m = tpkit::read_matches(score);
      std::vector<double> e, ok;
      Hidden hid;
      for (size_t r = 0; r < m.size(); ++r) {
        auto X = ground_of(scene, score_a - 1, m.xy(r, 0), m.xy(r, 1));
        if (!X) continue;
        const Seen k = seen_in(scene, score_b - 1, *X);
        hid.add(k);
        if (k != Seen::yes) continue;
        e.push_back((Eigen::Vector2d(m.xy(r, 2), m.xy(r, 3)) - scene.project(score_b - 1, *X)).norm());
        if (e.back() < 1) ok.push_back(e.back());
      }
      const Dist d = dist(e), c = dist(ok);
      std::printf("score %s: matches %zu, with truth %ld, correct (< 1 px) %ld, correct median %.4f p90 %.4f, all median %.4f p90 %.4f px\n",
                  score.c_str(), m.size(), d.n, c.n, c.med, c.p90, d.med, d.p90);
      hid.print("truth in view B");
      return 0;
    }
    if (!synth.empty()) {
      tpkit::SynthScene scene = tpkit::SynthScene::load(synth);
      print_scene(scene);
      std::string v[3] = {synth + "/view1.tif", synth + "/view2.tif", synth + "/view3.tif"};
      tpkit::ImageSource src[3];
      for (int k = 0; k < 3; ++k) src[k] = tpkit::open_image_source(v[k], 0, nodata, "");
      tpkit::PairMatchOptions po;
      po.threads = threads;
      po.lsm.window = window;
      po.lsm.taper = taper;
      po.choose_size = !size_given;
      po.lsm.l1 = !l2;
      po.guided = !global;
      if (no_retry) po.retry_windows.clear();
      if (quad >= 0) po.shape = quad != 0 ? tpkit::PairMatchOptions::Shape::quadratic : tpkit::PairMatchOptions::Shape::affine;
      if (cut >= 0) po.lsm.support = cut;
      if (adaptive >= 0) po.lsm.adaptive = adaptive != 0;
      if (epic >= 0) po.lsm.epipolar_curvature = epic != 0;
      if (tmin > 0) po.lsm.taper_min = tmin;
      if (tmax > 0) po.lsm.taper_max = tmax;
      if (cref > 0) po.lsm.curvature_ref = cref;
      if (tol > 0) po.lsm.tolerance = tol;
      if (stol > 0) po.lsm.stage_tolerance = stol;
      if (sit > 0) po.lsm.stage_iterations = sit;
      if (min_corr >= -1) po.lsm.min_corr = min_corr;
      if (contrast > 0) po.sift.contrast = contrast;
      if (max_sigma > 0) po.lsm.max_sigma = max_sigma;
      if (recheck >= 0) po.recheck_quantile = recheck;
      if (edge_share >= 0) po.edge_share = edge_share;
      if (sigma_scale > 0) po.lsm.sigma_scale = sigma_scale;
      if (sigma_floor >= 0) po.lsm.sigma_floor = sigma_floor;
      if (mask_k >= 0) po.lsm.mask_k = mask_k;
      if (mask_fit >= 0) po.lsm.mask_fit_k = mask_fit;
      if (sandwich >= 0) po.lsm.sigma_sandwich = sandwich != 0;
      std::vector<std::pair<double, double>> sig_err;  // refined matches: (sigma, squared error per coordinate)
      const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
      FILE* df = dump.empty() ? nullptr : std::fopen(dump.c_str(), "w");
      if (df)
        std::fprintf(df, "# pair x1 y1 ex ey kex key J11 J12 J21 J22 Hx_uu Hx_uv Hx_vv Hy_uu Hy_uv Hy_vv sigma corr tx2 ty2\n");
      std::vector<tpkit::Matches> ms;
      for (auto& p : pairs) {
        auto t0 = std::chrono::steady_clock::now();
        tpkit::PairMatchStats st;
        tpkit::Matches m = tpkit::match_pair(src[p[0]], src[p[1]], po, &st);
        double dt = secs(t0);
        std::vector<double> eraw, eref, eunref;
        int ckx = m.extra.find("kx2"), cky = m.extra.find("ky2"), crf = m.extra.find("refined");
        Hidden hid;
        for (size_t r = 0; r < m.size(); ++r) {
          auto X = ground_of(scene, p[0], m.xy(r, 0), m.xy(r, 1));
          if (!X) continue;
          const Seen k = seen_in(scene, p[1], *X);
          hid.add(k);
          if (k != Seen::yes) continue;
          Eigen::Vector2d tr = scene.project(p[1], *X);
          eraw.push_back((Eigen::Vector2d(m.extra.values(r, ckx), m.extra.values(r, cky)) - tr).norm());
          const bool unrefined = crf >= 0 && m.extra.values(r, crf) == 0;
          (unrefined ? eunref : eref).push_back((Eigen::Vector2d(m.xy(r, 2), m.xy(r, 3)) - tr).norm());
          if (!unrefined && m.extra.find("sigma") >= 0)
            sig_err.emplace_back(m.extra.values(r, m.extra.find("sigma")), 0.5 * eref.back() * eref.back());
          if (df) {
            // true local map f(d) = project(view 2, ground_point(view 1, p1 + d)): Jacobian and Hessians
            // by central differences (step 1 px)
            auto f = [&](double u, double v) -> Eigen::Vector2d {
              auto G = ground_of(scene, p[0], m.xy(r, 0) + u, m.xy(r, 1) + v);
              return G ? scene.project(p[1], *G) : Eigen::Vector2d(NAN, NAN);
            };
            const double hs = 1.0;
            Eigen::Vector2d f0 = f(0, 0), fu = f(hs, 0), fm = f(-hs, 0), fv = f(0, hs), fn = f(0, -hs);
            Eigen::Vector2d fuv = (f(hs, hs) - f(hs, -hs) - f(-hs, hs) + f(-hs, -hs)) / (4 * hs * hs);
            Eigen::Vector2d Ju = (fu - fm) / (2 * hs), Jv = (fv - fn) / (2 * hs);
            Eigen::Vector2d Huu = (fu - 2 * f0 + fm) / (hs * hs), Hvv = (fv - 2 * f0 + fn) / (hs * hs);
            Eigen::Vector2d e = Eigen::Vector2d(m.xy(r, 2), m.xy(r, 3)) - tr;
            Eigen::Vector2d ek = Eigen::Vector2d(m.extra.values(r, ckx), m.extra.values(r, cky)) - tr;
            int cs = m.extra.find("sigma"), cc = m.extra.find("corr");
            std::fprintf(df, "%d%d %.3f %.3f %.5f %.5f %.4f %.4f %.5f %.5f %.5f %.5f %.6f %.6f %.6f %.6f %.6f %.6f %.5f %.4f %.4f %.4f\n",
                         p[0] + 1, p[1] + 1, m.xy(r, 0), m.xy(r, 1), e.x(), e.y(), ek.x(), ek.y(), Ju.x(), Jv.x(), Ju.y(),
                         Jv.y(), Huu.x(), fuv.x(), Hvv.x(), Huu.y(), fuv.y(), Hvv.y(), m.extra.values(r, cs),
                         m.extra.values(r, cc), tr.x(), tr.y());
          }
        }
        std::printf("pair view%d-view%d: keypoints %ld/%ld, verified %ld, refined %ld, %.2f s\n", p[0] + 1, p[1] + 1,
                    st.keypoints1, st.keypoints2, st.verified, st.refined, dt);
        Dist dr = dist(eraw), df = dist(eref);
        print("raw SIFT (kx2, ky2)", dr);
        print("refined LSM (x2, y2)", df);
        print("kept unrefined (refined 0)", dist(eunref));
        hid.print("truth in image 2");
        ms.push_back(std::move(m));
      }
      if (df) std::fclose(df);
      if (deciles) print_sigma_deciles(sig_err, "refined matches, three pairs");
      tpkit::ChainOptions co;
      co.images = {v[0], v[1], v[2]};
      tpkit::ChainStats cs;
      tpkit::Tracks t = tpkit::chain_tracks(ms, co, &cs);
      std::vector<double> e2, e3;
      Eigen::Vector2d b2 = Eigen::Vector2d::Zero(), b3 = Eigen::Vector2d::Zero();
      Hidden hid2, hid3;
      for (size_t r = 0; r < t.size(); ++r) {
        auto X = ground_of(scene, 0, t.xy(r, 0), t.xy(r, 1));
        if (!X) continue;
        hid2.add(seen_in(scene, 1, *X));
        hid3.add(seen_in(scene, 2, *X));
        if (scene.visible(1, *X)) {
          Eigen::Vector2d d = t.point(r, 1) - scene.project(1, *X);
          e2.push_back(d.norm());
          if (d.norm() < 1) b2 += d;
        }
        if (scene.visible(2, *X)) {
          Eigen::Vector2d d = t.point(r, 2) - scene.project(2, *X);
          e3.push_back(d.norm());
          if (d.norm() < 1) b3 += d;
        }
      }
      std::printf("triplets (tp-chain): %zu\n", t.size());
      print("view 2 position", dist(e2));
      print("view 3 position", dist(e3));
      hid2.print("truth in view 2");
      hid3.print("truth in view 3");
      b2 /= std::max<size_t>(1, e2.size());
      b3 /= std::max<size_t>(1, e3.size());
      std::printf("  mean error (x, y), errors < 1 px: view 2 (%.4f, %.4f)  view 3 (%.4f, %.4f) px\n", b2.x(), b2.y(), b3.x(), b3.y());
      std::vector<double> all = e2;
      all.insert(all.end(), e3.begin(), e3.end());
      Dist da = dist(all);
      print("views 2+3", da);
      if (scene.has_structures()) {
        // the views 2+3 errors by the surface under view 1's point, and near an edge or not
        std::vector<double> by[4], edge, inside;
        const char* name[4] = {"  on the ground", "  on a roof", "  on a wall", "  on a crown"};
        for (size_t r = 0; r < t.size(); ++r) {
          auto X = ground_of(scene, 0, t.xy(r, 0), t.xy(r, 1));
          if (!X) continue;
          bool near = false;
          const int k = surface_class(scene, t.xy(r, 0), t.xy(r, 1), &near);
          for (int v = 1; v < 3; ++v)
            if (scene.visible(v, *X)) {
              const double e = (t.point(r, v) - scene.project(v, *X)).norm();
              by[k].push_back(e);
              (near ? edge : inside).push_back(e);
            }
        }
        for (int k = 0; k < 4; ++k) print(name[k], dist(by[k]));
        print("  within 5 px of an edge", dist(edge));
        print("  away from edges", dist(inside));
      }
      if (t.size() > 3) std::printf("  affine ML reprojection RMSE of the triplets %.4f px\n", affine_ml_rmse(t));
      // Consistency with the true cameras: the triplet's distance from the true three-view geometry,
      // i.e. the residuals of views 2 and 3 at the 3-D point that best explains all three positions
      // (Gauss-Newton on the true projections, from the ground point under x1). The strict error above
      // also counts where on the terrain the point lies: LSM's window averages the map over the
      // window, which on curved terrain puts the tie point at the window's mean height, a valid tie
      // point (consistent across the views) but not the one under x1.
      {
        std::vector<double> c23;
        for (size_t r = 0; r < t.size(); ++r) {
          auto X0 = ground_of(scene, 0, t.xy(r, 0), t.xy(r, 1));
          if (!X0) continue;
          Eigen::Vector3d X = *X0;
          auto res = [&](const Eigen::Vector3d& Y) {
            Eigen::Matrix<double, 6, 1> e;
            for (int k = 0; k < 3; ++k) e.segment<2>(2 * k) = scene.project(k, Y) - t.point(r, k);
            return e;
          };
          for (int it = 0; it < 6; ++it) {
            Eigen::Matrix<double, 6, 3> J;
            for (int c = 0; c < 3; ++c) {
              Eigen::Vector3d d = Eigen::Vector3d::Zero();
              d(c) = 0.01;
              J.col(c) = (res(X + d) - res(X - d)) / 0.02;
            }
            X -= (J.transpose() * J).ldlt().solve(J.transpose() * res(X));
          }
          const Eigen::Matrix<double, 6, 1> e = res(X);
          c23.push_back(e.segment<2>(2).norm());
          c23.push_back(e.segment<2>(4).norm());
        }
        print("consistency, views 2+3", dist(c23));
      }
      if (multi) multi_image(scene, v, src, t, threads, multi_t1, model_sigma, no_curv, multi_highpass, multi_taper, deciles);
      if (cmed > 0 && !(da.n > 0 && da.med <= cmed && da.p90 <= cp90)) {
        std::printf("FAIL: triplet median %.4f / p90 %.4f above %.4f / %.4f\n", da.med, da.p90, cmed, cp90);
        fail = true;
      }
    }
    return fail ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_match_accuracy: %s\n", e.what());
    return 1;
  }
}
