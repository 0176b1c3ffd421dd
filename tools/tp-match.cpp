// tp-match: sub-pixel tie points between two images (SIFT + affine F RANSAC + least-squares matching),
// or between every pair of several images.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <sstream>
#include <optional>
#include <thread>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/match/keypoint_cache.hpp"
#include "tpkit/match/match_every_pair.hpp"
#include "tpkit/match/match_pair.hpp"
#include "tpkit/match/match_region.hpp"
#include "tpkit/match/opencv_memory.hpp"
#include "tpkit/match/opencv_threads.hpp"
#include "tpkit/match/rpc_guided_matching.hpp"
#include "tpkit/match/tracks_coverage.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/core/tool_support.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::vector<std::string> images;
  std::string out = "-", mask1, mask2, coverage;
  int band = 0;  // --band N (from 1); 0: the image's default rendering (open_image_source)
  std::optional<double> nodata;
  int threads = 0;
  bool no_refine = false, drop_unrefined = false, no_mutual = false, global = false, l2 = false, quiet = false;
  tpkit::PairMatchOptions p;
  std::string retry_windows;  // --retry-windows W,W... | none
  std::optional<double> taper; // --taper (unset: auto)
  std::string shape = "auto";  // --shape
  bool quadratic = false;      // --quadratic (= --shape quadratic)
  std::vector<long> region;  // --region X0 Y0 W H
  double region_margin = 128;
  int detect = 0;  // --detect N: image N's detection tiles into the cache
  std::string geometry, write_geometry;
  std::vector<std::string> rpc_files;  // --rpc IMG=FILE
  bool no_rpc = false, rpc_guided = false;
  std::vector<double> height_range;
  std::vector<tpkit::RpcModel> rpc;  // image k's model (rpc_of[k] points here)
  std::vector<const tpkit::RpcModel*> rpc_of;
};

// The RPC models of the images (a sidecar, the tag or --rpc): RPC-guided search when every image of a
// pair has one, unless --no-rpc or --global; --rpc-guided asks for it and fails without models.
void load_rpcs(Opts& o) {
  o.rpc_of.assign(o.images.size(), nullptr);
  if (o.no_rpc || o.global) return;
  const auto overrides = tpkit::resolve_rpc_overrides(tpkit::parse_rpc_overrides(o.rpc_files), o.images);
  o.rpc.reserve(o.images.size());
  for (size_t k = 0; k < o.images.size(); ++k) {
    if (o.rpc_guided) {
      o.rpc.push_back(tpkit::load_image_rpc(o.images[k], overrides).model);
    } else if (auto s = tpkit::find_image_rpc(o.images[k], overrides)) {
      o.rpc.push_back(s->model);
    } else {
      continue;
    }
    o.rpc_of[k] = &o.rpc.back();
  }
  o.p.rpc_only = o.rpc_guided;
  if (!o.height_range.empty()) {
    o.p.rpc_guide.height_given = true;
    o.p.rpc_guide.h_lo = o.height_range[0], o.p.rpc_guide.h_hi = o.height_range[1];
  }
  if (o.images.size() == 2) o.p.rpc1 = o.rpc_of[0], o.p.rpc2 = o.rpc_of[1];
  if (!(o.p.rpc1 && o.p.rpc2)) o.p.rpc1 = o.p.rpc2 = nullptr;
  for (size_t i = 0; i < o.images.size(); ++i)  // the heights of every RPC pair, before any work
    for (size_t j = i + 1; j < o.images.size(); ++j)
      if (o.rpc_of[i] && o.rpc_of[j]) {
        double lo, hi;
        tpkit::rpc_height_range(*o.rpc_of[i], *o.rpc_of[j], o.p.rpc_guide, lo, hi);
      }
}

// Two images and --region / --write-geometry: the region run or the geometry of the pair.
int region_or_geometry_run(const Opts& o, const std::vector<tpkit::ImageSource>& src,
                           const std::function<void(const std::string&, const tpkit::PairMatchStats&)>& report) {
  if (!o.write_geometry.empty()) {
    tpkit::save_pair_geometry(o.write_geometry, tpkit::estimate_pair_geometry(src[0], src[1], o.p.sift, {}));
    return 0;
  }
  tpkit::PairGeometry G;
  if (!o.geometry.empty()) {
    G = tpkit::read_pair_geometry(o.geometry);
    tpkit::check_pair_geometry(G, o.geometry, src[0], src[1], o.p.sift);
  } else if (o.detect > 0) {  // the stretch is all a detection job needs
    G.stretch1 = tpkit::percentile_stretch(src[0], o.p.sift.stretch_lo, o.p.sift.stretch_hi);
    G.stretch2 = tpkit::percentile_stretch(src[1], o.p.sift.stretch_lo, o.p.sift.stretch_hi);
  } else {
    G = tpkit::estimate_pair_geometry(src[0], src[1], o.p.sift, {});
  }
  if (o.detect > 0) {  // a detection job: image N's tiles that start in the window, into the cache
    const tpkit::ImageSource& s = src[static_cast<size_t>(o.detect - 1)];
    const auto grid = tpkit::tile_grid(s.info.width, s.info.height, o.p.sift.tile, o.p.sift.overlap);
    const auto tiles = tpkit::tiles_starting_in(grid, o.region[0], o.region[1], o.region[2], o.region[3]);
    if (tiles.empty())
      throw tpkit::UsageError("--detect " + std::to_string(o.detect) + " --region: no detection tile of " + s.path +
                              " starts in the window");
    const auto entries = tpkit::cache_detection_tiles(s, o.p.sift, o.detect == 1 ? G.stretch1 : G.stretch2, tiles,
                                                      o.p.threads, o.p.cache_dir);
    tpkit::save_detection_report(o.out, s, o.p.sift, o.p.cache_dir, entries);
    if (!o.quiet) {
      long k = 0, c = 0;
      for (const auto& e : entries) k += e.keypoints, c += e.cached ? 1 : 0;
      tpkit::summary(s.path + ": " + std::to_string(entries.size()) + " detection tiles (" + std::to_string(c) +
                     " already cached), " + std::to_string(k) + " keypoints");
    }
    return 0;
  }
  tpkit::RegionOptions r;
  r.window = {o.region[0], o.region[1], o.region[2], o.region[3]};
  r.margin = o.region_margin;
  tpkit::PairMatchStats st;
  tpkit::Matches m = tpkit::match_region(src[0], src[1], G, o.p, r, &st);
  tpkit::save_matches(o.out, m);
  report(o.images[0] + " and " + o.images[1], st);
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-match", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("IMAGES", o->images, "IMG1 IMG2 (image 1 is the template side), or three or more images: every pair")
            ->required()
            ->expected(2, 1 << 16);
        app.add_option("-o,--output", o->out, "output matches file (- = stdout); with more than two images, a folder");
        app.add_option("--coverage", o->coverage, "SVG figure: matches per cell over each image's thumbnail (two images)");
        app.add_option("--band", o->band, "band, from 1 (default: the luminance of an RGB image, the mean of a multispectral one)")->check(tpkit::Positive);
        app.add_option("--nodata", o->nodata, "nodata grey level (default: the GDAL_NODATA tag)");
        app.add_option("--mask1", o->mask1, "mask image of IMG1 (0 = invalid)");
        app.add_option("--mask2", o->mask2, "mask image of IMG2 (0 = invalid)");
        app.add_option("--threads", o->threads, "worker threads (0 = all cores)")->check(CLI::Range(0, tpkit::kMaxThreads));
        app.add_option("--cache", o->p.cache_dir, "keypoint cache folder: each image is detected once");
        app.add_option("--tile", o->p.sift.tile, "detection tile size, pixels")->check(CLI::Range(256L, 1L << 20));
        app.add_option("--overlap", o->p.sift.overlap, "detection tile overlap, pixels")->check(CLI::Range(16L, 4096L));
        app.add_option("--max-per-tile", o->p.sift.max_per_tile, "strongest keypoints kept per tile (0 = all)")->check(tpkit::NonNegative);
        app.add_option("--contrast", o->p.sift.contrast, "SIFT contrast threshold")->check(tpkit::Positive);
        app.add_option("--edge", o->p.sift.edge, "SIFT edge threshold")->check(tpkit::Positive);
        app.add_option("--stretch", [o](CLI::results_t r) {
          double v[2] = {0, 0};
          for (int k = 0; k < 2; ++k) {
            const std::string& t = r.at(static_cast<size_t>(k));
            char* end = nullptr;
            v[k] = std::strtod(t.c_str(), &end);
            if (t.empty() || *end != '\0' || !std::isfinite(v[k]))
              throw CLI::ValidationError("--stretch", "LOW HIGH are percentiles, got '" + t + "'");
          }
          o->p.sift.stretch_lo = v[0];
          o->p.sift.stretch_hi = v[1];
          return true;
        }, "low and high percentiles of the 8-bit rendering")->expected(2);
        app.add_option("--ratio", o->p.desc.ratio, "nearest-neighbour ratio test")->check(CLI::Range(0.1, 1.0));
        app.add_flag("--no-mutual", o->no_mutual, "skip the mutual nearest-neighbour check");
        app.add_option("--exact-below", o->p.desc.exact_below, "exact search when both sets are smaller")->check(tpkit::NonNegative);
        app.add_option("--checks", o->p.desc.flann_checks, "leaves visited by the approximate search")->check(tpkit::Positive);
        app.add_flag("--global", o->global, "search every descriptor pair instead of the epipolar band");
        app.add_option("--epipolar-band", o->p.guide.band, "guided search: pixels across the epipolar line")->check(tpkit::Positive);
        app.add_option("--parallax-margin", o->p.guide.parallax_margin, "guided search: pixels added to each parallax range")
            ->check(tpkit::NonNegative);
        app.add_option("--ratio-region", o->p.guide.ratio_margin, "guided search: the ratio test's region is this much wider, pixels")
            ->check(tpkit::NonNegative);
        app.add_option("--threshold", o->p.ransac_threshold, "RANSAC inlier distance, pixels")->check(tpkit::Positive);
        app.add_option("--iterations", o->p.ransac_iterations, "RANSAC iterations at most")->check(tpkit::Positive);
        app.add_option("--seed", o->p.seed, "RANSAC seed");
        app.add_option("--min-inliers", o->p.min_inliers, "fewer verified matches = no overlap")->check(tpkit::Positive);
        app.add_option("--grid", o->p.grid, "grid cells per side for even spread (0 = off)")->check(tpkit::NonNegative);
        app.add_option("--per-cell", o->p.per_cell, "matches kept per grid cell")->check(tpkit::Positive);
        app.add_flag("--no-refine", o->no_refine, "keep raw SIFT positions");
        CLI::Option* window = app.add_option("--window", o->p.lsm.window, "LSM window size, pixels (odd; given, the size is not chosen)")->check(CLI::Range(5, 101));
        app.add_option("--retry-windows", o->retry_windows, "LSM windows, pixels, tried in turn where --window's refinement failed on its content (default 15,31,41; none: no retry)");
        app.add_option("--size-recheck", o->p.recheck_quantile,
                       "with a larger window size chosen: matches whose sigma there is above this quantile of the pair's, and those it failed on, "
                       "refined again at the smaller sizes, the lowest sigma kept (default 0.9; 1 = none)")
            ->check(CLI::Range(0.0, 1.0));
        app.add_option("--edge-share", o->p.edge_share,
                       "a keypoint whose windows all leave the image: its window cut to the pixels inside both images where they hold at least "
                       "this share of the taper's weight (default 0.4; 0 = never)")
            ->check(CLI::Range(0.0, 1.0));
        app.add_option("--max-shift", o->p.lsm.max_shift, "reject refinements farther from SIFT, pixels")->check(tpkit::Positive);
        app.add_option("--max-sigma", o->p.lsm.max_sigma, "reject refinements whose sigma is larger, pixels")->check(tpkit::Positive);
        app.add_option("--min-corr", o->p.lsm.min_corr, "reject refinements with a lower final correlation")->check(CLI::Range(-1.0, 1.0));
        app.add_option("--residual-mask", o->p.lsm.mask_k,
                       "LSM: pixels whose residual exceeds K robust sigmas are left out of the correlation (0 = off)")
            ->check(tpkit::NonNegative);
        app.add_option("--fit-mask", o->p.lsm.mask_fit_k,
                       "LSM: pixels whose residual exceeds K robust sigmas lose their weight in the fit (default 4; 0 = off)")
            ->check(tpkit::NonNegative);
        app.add_option("--sigma-scale", o->p.lsm.sigma_scale, "LSM sigma calibration: factor on the normal equations' sigma")
            ->check(tpkit::Positive);
        app.add_option("--sigma-floor", o->p.lsm.sigma_floor, "LSM sigma calibration: floor added in quadrature, pixels")
            ->check(tpkit::NonNegative);
        app.add_option("--unrefined-sigma", o->p.unrefined_sigma, "least sigma of a match kept unrefined, pixels")->check(tpkit::Positive);
        app.add_flag("--drop-unrefined", o->drop_unrefined, "drop verified matches whose refinement is rejected (counted by reason)");
        app.add_option("--blur", tpkit::auto_or_pixels(o->p.blur, "--blur", -10, 10),
                       "relative blur before refinement: auto (default), 0 none, > 0 blurs IMG1, < 0 IMG2, pixels")
            ->type_name("auto|SIGMA");
        app.add_option("--highpass", tpkit::auto_or_pixels(o->p.highpass, "--highpass", 0, 10),
                       "local mean subtracted from both images before refinement: auto (default), 0 none, Gaussian sigma in pixels")
            ->type_name("auto|SIGMA");
        app.add_option("--taper", tpkit::auto_or_pixels(o->taper, "--taper", 0, 30),
                       "Gaussian weight of the LSM window: auto (default: the size chosen on a sample of the pair's matches), sigma in pixels (0 = flat)")
            ->type_name("auto|PX");
        app.add_flag("--l2", o->l2, "plain least squares instead of robust L1");
        app.add_option("--shape", o->shape, "LSM window model: auto (default: chosen on a sample of the pair's matches), affine, or quadratic (the map bends along the epipolar lines)")
            ->check(CLI::IsMember({"auto", "affine", "quadratic"}));
        app.add_flag("--quadratic", o->quadratic, "the same as --shape quadratic");
        app.add_option("--region", [o](CLI::results_t r) {
          o->region.clear();
          for (const auto& v : r) {
            size_t used = 0;
            long x = 0;
            try {
              x = std::stol(v, &used);
            } catch (const std::exception&) {
              used = 0;
            }
            if (used == 0 || used != v.size()) throw CLI::ValidationError("--region", "X0 Y0 W H are whole pixels, got '" + v + "'");
            o->region.push_back(x);
          }
          return true;
        }, "X0 Y0 W H: match only image-1 keypoints in this window, image-1 pixels")->expected(4);
        app.add_option("--region-margin", o->region_margin, "with --region: pixels matched beyond the window for context")
            ->check(tpkit::NonNegative);
        app.add_option("--detect", o->detect, "N (1 or 2), with --region and --cache: detect image N's tiles that start in the window "
                                              "(image-N pixels) into the cache, write a detection report, and stop")
            ->check(CLI::Range(1, 2));
        app.add_option("--geometry", o->geometry, "with --region: pair geometry file written by --write-geometry");
        app.add_option("--write-geometry", o->write_geometry, "write the pair geometry file (coarse map, stretches) and stop");
        app.add_option("--rpc", o->rpc_files, "IMG=FILE: the RPC model of IMG (txt, RPB, DIMAP XML or TIFF tag)");
        app.add_flag("--no-rpc", o->no_rpc, "do not use the images' RPC models: the coarse stage finds the geometry");
        app.add_flag("--rpc-guided", o->rpc_guided, "search along the RPC epipolar curves; fail if an image has no model");
        app.add_option("--height-range", o->height_range, "LO HI: heights searched with RPCs, metres above the ellipsoid")
            ->expected(2);
        app.add_option("--rpc-margin", o->p.rpc_guide.margin, "RPC-guided search: pixels around the epipolar curve, first try")
            ->check(tpkit::NonNegative);
        app.add_option("--rpc-max-margin", o->p.rpc_guide.max_margin,
                       "RPC-guided search: widest margin tried (4-fold steps) while the models' bias needs it, pixels")
            ->check(tpkit::NonNegative);
        app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
        return [o, window]() {
          if (o->p.sift.stretch_lo < 0 || o->p.sift.stretch_hi > 100 || !(o->p.sift.stretch_lo < o->p.sift.stretch_hi))
            throw tpkit::UsageError("--stretch needs 0 <= LOW < HIGH <= 100");
          if (o->p.lsm.window % 2 == 0) throw tpkit::UsageError("--window must be odd");
          // a size given (--window, or --taper with a number) is used as given
          if (o->taper) o->p.lsm.taper = *o->taper;
          o->p.choose_size = !o->taper && window->count() == 0;
          if (o->quadratic && o->shape == "affine") throw tpkit::UsageError("--quadratic contradicts --shape affine");
          o->p.shape = o->quadratic || o->shape == "quadratic" ? tpkit::PairMatchOptions::Shape::quadratic
                       : o->shape == "affine"                   ? tpkit::PairMatchOptions::Shape::affine
                                                                : tpkit::PairMatchOptions::Shape::automatic;
          if (!o->retry_windows.empty()) {
            o->p.retry_windows.clear();
            if (o->retry_windows != "none") {
              std::stringstream ss(o->retry_windows);
              for (std::string t; std::getline(ss, t, ',');) {
                char* end = nullptr;
                const long w = std::strtol(t.c_str(), &end, 10);
                if (t.empty() || *end != '\0' || w < 5 || w > 101 || w % 2 == 0)
                  throw tpkit::UsageError("--retry-windows '" + o->retry_windows + "': odd window sizes of 5 to 101 pixels, comma-separated, or none");
                o->p.retry_windows.push_back(static_cast<int>(w));
              }
            }
          }
          o->p.desc.mutual = !o->no_mutual;
          o->p.guided = !o->global;
          o->p.refine = !o->no_refine;
          o->p.keep_unrefined = !o->drop_unrefined;
          o->p.lsm.l1 = !o->l2;
          o->p.threads = o->threads > 0 ? o->threads : std::max(1u, std::thread::hardware_concurrency());
          o->p.threads = std::min(o->p.threads, tpkit::kMaxThreads);
          tpkit::set_opencv_threads(o->p.threads);
          tpkit::use_large_page_mat_allocator();
          o->p.progress = !o->quiet;
          const size_t n = o->images.size();
          if (n > 2 && (o->out == "-" || o->out.empty()))
            throw tpkit::UsageError("with more than two images, -o must name a folder for the pair files");
          if (n > 2 && (!o->mask1.empty() || !o->mask2.empty()))
            throw tpkit::UsageError("--mask1 / --mask2 apply to two images only");
          if ((!o->region.empty() || !o->write_geometry.empty()) && n != 2)
            throw tpkit::UsageError("--region and --write-geometry take two images");
          if (!o->geometry.empty() && o->region.empty()) throw tpkit::UsageError("--geometry goes with --region");
          if (!o->coverage.empty() && (n != 2 || !o->region.empty() || !o->write_geometry.empty() || o->detect > 0))
            throw tpkit::UsageError("--coverage draws one pair's matches: two images, no --region, --detect or --write-geometry (tp-chain --coverage draws a block's tracks)");
          if (o->detect > 0 && (o->region.empty() || o->p.cache_dir.empty()))
            throw tpkit::UsageError("--detect needs --region (the window of image " + std::to_string(o->detect) + ") and --cache");
          if (o->detect > 0 && !o->write_geometry.empty()) throw tpkit::UsageError("--detect and --write-geometry are separate runs");
          if (o->detect > 0 && (o->out == "-" || o->out.empty()))
            throw tpkit::UsageError("--detect writes its report to the file named by -o");
          if (!o->write_geometry.empty() && !o->region.empty()) throw tpkit::UsageError("--write-geometry and --region are separate runs");
          if (o->no_rpc && o->rpc_guided) throw tpkit::UsageError("--no-rpc and --rpc-guided exclude each other");
          if (o->global && o->rpc_guided) throw tpkit::UsageError("--global and --rpc-guided exclude each other");
          std::vector<std::string> inputs = o->images;
          inputs.push_back(o->mask1);
          inputs.push_back(o->mask2);
          inputs.push_back(o->geometry);
          if (!o->write_geometry.empty())
            tpkit::check_outputs({{"--write-geometry", o->write_geometry}}, inputs);
          else if (n == 2)
            tpkit::check_outputs({{"-o", o->out}, {"--coverage", o->coverage}}, inputs);
          std::vector<tpkit::ImageSource> src;
          for (size_t i = 0; i < n; ++i)
            src.push_back(tpkit::open_image_source(o->images[i], o->band > 0 ? std::optional<int>(o->band - 1) : std::nullopt, o->nodata, i == 0 ? o->mask1 : i == 1 ? o->mask2 : ""));
          load_rpcs(*o);
          auto report = [&](const std::string& what, const tpkit::PairMatchStats& st) {
            if (!st.overlap)
              tpkit::warn("no verified matches between " + what + " (" + tpkit::no_match_reason(st, o->p) +
                          "): writing a file with zero records");
            if (st.rpc_fallback)
              tpkit::warn("the RPC epipolar curves of " + what + " " + tpkit::rpc_fallback_reason(st, o->p));
            if (st.no_parallax)
              tpkit::warn(what + " have no parallax (the same image, or views without a base): matches verified by a "
                          "2-D affine map; they carry no 3-D information");
            if (o->quiet) return;
            std::ostringstream line;
            line << (n > 2 ? what + ": " : std::string()) << "keypoints " << st.keypoints1 << (st.cached1 ? " (cached)" : "")
                 << " / " << st.keypoints2 << (st.cached2 ? " (cached)" : "") << ", putative " << st.putative << ", verified "
                 << st.verified << " (rms " << st.ransac_rms << " px)";
            if (o->p.grid > 0) line << ", after grid " << st.gridded;
            if (o->p.refine) {
              line << ", refined " << st.refined;
              for (const auto& [what, count] : {std::pair<const char*, const long*>{" (kept unrefined:", st.unrefined},
                                                std::pair<const char*, const long*>{" (dropped:", st.dropped}}) {
                const char* sep = what;
                for (int k = 1; k < tpkit::kLsmStatusCount; ++k)
                  if (count[k]) {
                    line << sep << " " << tpkit::to_string(static_cast<tpkit::LsmStatus>(k)) << " " << count[k];
                    sep = ",";
                  }
                if (std::string(sep) == ",") line << ")";
              }
            }
            line << "; seconds: detect " << st.seconds[0] << ", match " << st.seconds[1] << ", verify " << st.seconds[2]
                 << ", refine " << st.seconds[3];
            tpkit::summary(line.str());
          };
          if (n == 2 && (!o->region.empty() || !o->write_geometry.empty())) return region_or_geometry_run(*o, src, report);
          if (n == 2) {
            tpkit::PairMatchStats st;
            tpkit::Matches m = tpkit::match_pair(src[0], src[1], o->p, &st);
            if (!o->coverage.empty()) tpkit::save_matches_coverage(o->coverage, m);
            tpkit::save_matches(o->out, m);
            report(o->images[0] + " and " + o->images[1], st);
            return 0;
          }
          // every pair: each image detected once, the first pairs matched while the last images are detected
          tpkit::create_output_dir(o->out);  // removed again if the run fails
          double detect_s = 0;
          tpkit::match_every_pair(
              src, o->p, o->rpc_of,
              [&](size_t i, size_t j, tpkit::Matches& m, const tpkit::PairMatchStats& st) {
                const std::string f =
                    (std::filesystem::path(o->out) / ("pair-" + std::to_string(i + 1) + "-" + std::to_string(j + 1) + ".matches")).string();
                tpkit::save_matches(f, m);
                report(f, st);
              },
              &detect_s);
          if (!o->quiet) {
            std::ostringstream line;
            line << "detection of the " << n << " images ended after " << detect_s << " s";
            tpkit::summary(line.str());
          }
          return 0;
        };
      },
      tpkit_man_page);
}
