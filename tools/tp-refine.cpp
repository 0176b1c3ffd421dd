// tp-refine: every view of every track refined together, constrained by the images' RPC models
// (multi-image least-squares matching, man/tp-refine.1).
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/match/image_tiles.hpp"
#include "tpkit/match/multi_image_lsm.hpp"
#include "tpkit/match/radiometric_highpass.hpp"
#include "tpkit/rpc/rpc_io.hpp"

extern const char* const tpkit_man_page;

namespace {
using namespace tpkit;

struct Opts {
  std::vector<std::string> images, rpc;
  std::string tracks, out = "-", bias = "affine", reference, model_sigma = "auto";
  std::optional<double> highpass;  // --highpass SIGMA; unset: auto
  int threads = 1;
  bool quiet = false, no_curvature = false, no_extend = false;
  MultiLsmOptions lsm;
};

int run(const Opts& o) {
  if (o.images.size() < 2) throw UsageError("at least two images are needed");
  if (o.tracks.empty()) throw UsageError("--tracks: a tracks file is needed");
  if (o.threads < 1 || o.threads > kMaxThreads) throw UsageError("--threads must be between 1 and " + std::to_string(kMaxThreads));
  if (o.lsm.window < 5 || o.lsm.window % 2 == 0) throw UsageError("--window must be odd and at least 5, got " + std::to_string(o.lsm.window));
  const BiasModel bias_model = parse_bias_model(o.bias);
  std::vector<std::string> inputs = o.images;
  inputs.push_back(o.tracks);
  check_outputs({{"-o", o.out}}, inputs);
  const Tracks t = read_tracks(o.tracks);
  const int K = t.views();
  // the image of each column pair, among the images given (as rpc-adjust and tp-ground name them)
  std::vector<std::string> paths(K);
  for (int k = 0; k < K; ++k) {
    const int i = image_index(t.images[k].path, o.images, o.tracks);
    if (i < 0)
      throw InputError(o.tracks, 0, "image" + std::to_string(k + 1) + " " + t.images[k].path + (i == -2 ? " is ambiguous among" : " is not one of") + " the images given");
    paths[k] = o.images[i];
  }
  int reference = 0;
  if (!o.reference.empty()) {
    reference = image_index(o.reference, paths);
    if (reference < 0) throw UsageError("--reference " + o.reference + ": not one of the tracks' images");
  }
  const auto overrides = resolve_rpc_overrides(parse_rpc_overrides(o.rpc), o.images);
  std::vector<RpcModel> models(K);
  std::vector<Raster> rasters(K);
  for (int k = 0; k < K; ++k) {
    models[k] = load_image_rpc(paths[k], overrides).model;
    // the grey level tp-match reads (a band, or the luminance of RGB), invalid pixels NaN; whole images
    const ImageSource src = open_image_source(paths[k], std::nullopt, std::nullopt, "");
    rasters[k] = read_valid_region(src, 0, 0, src.info.width, src.info.height);
  }
  std::vector<const RpcModel*> mp;
  for (const auto& m : models) mp.push_back(&m);
  std::vector<double> bias_rms;
  const std::vector<ImageBias> bias = estimate_track_biases(t, mp, bias_model, reference, 4, &bias_rms);
  std::vector<MultiLsmImage> images(K);
  for (int k = 0; k < K; ++k) images[k] = {&rasters[k], &models[k], bias[k], bias_rms[k] / std::sqrt(2.0)};
  MultiLsmOptions lo = o.lsm;
  if (o.model_sigma != "auto") {
    char* end = nullptr;
    lo.model_sigma = std::strtod(o.model_sigma.c_str(), &end);
    if (o.model_sigma.empty() || *end != '\0' || !(lo.model_sigma >= 0) || !std::isfinite(lo.model_sigma))
      throw UsageError("--model-sigma: 'auto' or a number of pixels >= 0, got '" + o.model_sigma + "'");
  }
  lo.curvature = !o.no_curvature;
  lo.extend = !o.no_extend;
  // images of other dates: each image's local mean out before the refinement (tp-match's --highpass),
  // chosen on a sample of the tracks unless given
  HighpassChoice hp;
  if (o.highpass) hp.sigma = *o.highpass;
  else hp = choose_track_highpass(t, images, lo, o.threads);
  for (auto& r : rasters) highpass_raster(r, hp.sigma);
  // the window's size: the larger (with the fallback) where a sample of the tracks shows no bias from it
  WindowSizeChoice size;
  size.size = {lo.taper, lo.window, false};
  size.shapes = false;
  if (lo.fallback_window > 0) {
    size = choose_track_size(t, images, lo, o.threads);
    use_track_size(size, lo);
  }
  MultiLsmStats st;
  Tracks out = refine_tracks(t, images, lo, o.threads, &st);
  if (out.size() == 0) throw InputError(o.tracks, 0, "no track kept a second view after the refinement");
  out.meta.push_back({"refined", "tp-refine multi-image LSM (bias " + o.bias + ", model sigma " + o.model_sigma + (lo.extend ? ", extended to the images each track lacks" : "") +
                          ", window " + std::to_string(lo.window) + " px taper " + format_number(lo.taper) + " px" +
                          (lo.fallback_window > 0 ? " (" + std::to_string(lo.fallback_window) + " px taper " + format_number(lo.fallback_taper) + " px for the " +
                                                        std::to_string(st.tracks_at_fallback) + " tracks that kept more views there)"
                                                  : std::string()) + ")"});
  out.meta.push_back({"highpass", describe_track_highpass(hp, o.highpass.has_value())});
  out.meta.push_back({"size", describe_window_size(size, size.tried.empty(), "", "sampled tracks")});
  AtomicOutput f(o.out);
  write_tracks(f.stream(), out);
  f.commit();
  if (!o.quiet) {
    std::ostringstream s;
    s << st.tracks << " tracks, " << st.views << " views: " << st.tracks_written << " tracks written, " << st.tracks_dropped
      << " dropped (fewer than 2 views left); views refined " << st.views_refined << " (" << st.views_added << " of them added), dropped " << st.views_dropped;
    if (lo.fallback_window > 0)
      s << "; window " << lo.window << " px (taper " << format_number(lo.taper) << "), " << st.tracks_at_fallback << " tracks at " << lo.fallback_window
        << " px (taper " << format_number(lo.fallback_taper) << ")";
    std::string sep = " (";
    for (int i = 0; i < kMultiLsmStatusCount; ++i)
      if (st.by_status[i] > 0) s << sep << to_string(static_cast<MultiLsmViewStatus>(i)) << " " << st.by_status[i], sep = ", ";
    if (sep == ", ") s << ", the others the templates of dropped tracks)";
    s << "; template per image:";
    for (long n : st.template_count) s << " " << n;
    s << "; bias fit residual RMS per image (px, the first the reference's offsets):";
    for (int k = 0; k < K; ++k) s << " " << (std::isnan(bias_rms[k]) ? std::string("-") : std::to_string(bias_rms[k]).substr(0, 5));
    s << "; highpass " << format_number(hp.sigma) << " px";
    summary(s.str());
  }
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-refine", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("images", o->images, "the images of the tracks (their RPCs: tag 50844 or a sidecar beside them)");
        app.add_option("--tracks", o->tracks, "tracks file (tp-chain)");
        app.add_option("--rpc", o->rpc, "IMAGE=FILE: the RPC model of IMAGE from FILE (repeatable)");
        app.add_option("--bias", o->bias, "bias of each image estimated from the tracks: shift, drift or affine");
        app.add_option("--reference", o->reference, "image whose bias is zero (default: the tracks' first)");
        CLI::Option* window = app.add_option("--window", o->lsm.window, "template block, pixels (odd; default: chosen on a sample of the tracks, 29 or 21; given, used alone)");
        CLI::Option* taper = app.add_option("--taper", o->lsm.taper, "Gaussian weight of the window's pixels, pixels (default: chosen, 5 or 3; given, used alone)")->check(tpkit::Positive);
        app.add_option("--model-sigma", o->model_sigma, "prior deviation of a view from the models, pixels (0: hard constraint; auto: each image's bias fit residual)");
        app.add_flag("--no-extend", o->no_extend, "refine only the views each track has (default: also those in the images it lacks, where its ground point projects inside them)");
        app.add_flag("--no-curvature", o->no_curvature, "a planar surface under each window (3 unknowns, not 6)");
        app.add_option("--max-shift", o->lsm.max_shift, "drop a view moved farther than this from its input, pixels")->check(tpkit::Positive);
        app.add_option("--max-sigma", o->lsm.max_sigma, "drop a view whose sigma is larger, pixels")->check(tpkit::Positive);
        app.add_option("--min-corr", o->lsm.min_corr, "drop a view whose correlation with the template is lower");
        app.add_option("--highpass", tpkit::auto_or_pixels(o->highpass, "--highpass", 0, 10), "auto or SIGMA: subtract each image's local mean (Gaussian of SIGMA pixels) first; 0 = none; auto: chosen on a sample of the tracks");
        app.add_option("--threads", o->threads, "threads");
        app.add_option("-o,--output", o->out, "refined tracks file (- = stdout)");
        app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
        return [o, window, taper]() {
          // a size given is used alone
          if (window->count() > 0 || taper->count() > 0) o->lsm.fallback_window = 0;
          return run(*o);
        };
      },
      tpkit_man_page);
}
