// rpc-adjust: bias compensation of RPC cameras from tie points (man/rpc-adjust.1).
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/rpc/adjust_plot.hpp"
#include "tpkit/rpc/ground_export.hpp"
#include "tpkit/rpc/dem_prior.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_ground.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/ground/gcp_file.hpp"
#include "tpkit/ground/ground_accuracy.hpp"

extern const char* const tpkit_man_page;

namespace {
namespace fs = std::filesystem;
using namespace tpkit;

struct Opts {
  std::vector<std::string> images, tracks, check, fixed, rpc, gcp;
  std::string model = "affine", height_prior, dem, dem_datum, crs = "geographic", out;
  double dem_sigma = NAN, loss = 1, flag = 1, prior_shift = 100, prior_linear = 0.01, default_sigma = NAN;
  int threads = 1, iterations = 100;
  bool write_tiff = false, strict = false, unweighted = false, force_gcp = false;
};


std::vector<AdjustImage> load_images(const Opts& o, std::vector<RpcSource>& sources) {
  const auto overrides = resolve_rpc_overrides(parse_rpc_overrides(o.rpc), o.images);
  std::vector<AdjustImage> out;
  std::set<std::string> stems;
  for (const auto& path : o.images) {
    AdjustImage im;
    im.path = path;
    ImageInfo info = image_info(path);
    im.width = info.width;
    im.height = info.height;
    sources.push_back(load_image_rpc(path, overrides));
    im.model = sources.back().model;
    if (!stems.insert(fs::path(path).stem().string()).second)
      throw UsageError("two images named " + fs::path(path).stem().string() + ": their adjusted models would share a name in -o");
    out.push_back(im);
  }
  for (const auto& f : o.fixed) {
    const int i = image_index(f, o.images);  // as --rpc and the tracks files name the images
    if (i < 0) throw UsageError("--fixed " + f + ": " + (i == -2 ? "ambiguous among" : "not one of") + " the images");
    out[static_cast<size_t>(i)].fixed = true;
  }
  return out;
}

std::string models_line(const std::vector<RpcSource>& s, size_t i) {
  return s[i].path + " (" + rpc_form_name(s[i].form) + ")";
}

// ground.points, ground.geojson and ground.csv (+ .csvt, .prj): one table, three forms (ground_export.hpp).
void write_points(const fs::path& dir, const Opts& o, const std::vector<AdjustImage>& images,
                  const std::vector<RpcSource>& sources, const std::vector<AdjustTrack>& tracks, const AdjustResult& r) {
  const RpcModel& m0 = images[0].model;
  GroundConverter conv(parse_ground_crs(o.crs), m0.lon_off, m0.lat_off);
  GroundTable table;
  for (const auto& im : images) table.images.push_back({im.path, im.width, im.height});
  Meta& meta = table.meta;
  for (size_t i = 0; i < images.size(); ++i) meta_set(meta, "model" + std::to_string(i + 1), models_line(sources, i) + " + bias");
  meta_set(meta, "sigma_h", "standard deviation of h (m) for the a posteriori image noise sigma0 = " + format_number(r.sigma0) + " px");
  meta_set(meta, "rms_px", "RMS over the track's views of the residual after the adjustment (pixels)");
  meta_set(meta, "flagged", "1: rms_px above --flag " + format_number(o.flag) + " px");
  meta_set(meta, "views", "the views in the fit (less those dropped as blunders: rpc.residuals column dropped)");
  table.columns = {{"sigma_h", false}, {"views", true}, {"rms_px", false}, {"flagged", true}};
  for (size_t t = 0; t < tracks.size(); ++t) {
    if (!r.initial_ok[t]) continue;
    table.points.push_back({tracks[t].id, r.ground[t],
                            {r.sigma_h[t], static_cast<double>(tracks[t].views.size() - r.views_dropped[t]), r.rms_after[t],
                             static_cast<double>(r.flagged[t])}});
  }
  for (const char* name : {"ground.points", "ground.geojson", "ground.csv"}) write_ground((dir / name).string(), table, conv);
}

void write_residuals(const std::string& path, const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                     const AdjustResult& r, double check_rms, long check_n) {
  std::vector<ImageRef> refs;
  for (const auto& im : images) refs.push_back({im.path, im.width, im.height});
  Meta meta;
  meta_set(meta, "residual", "projected minus observed, pixels; before: zero bias and the least-squares point of "
                             "the delivered models; after: the adjusted biases and points");
  meta_set(meta, "sigma", "the standard deviation the observation was weighted with (pixels: given, floored at " +
                              format_number(kMinObservationSigma) + ", or the default)");
  meta_set(meta, "dropped", "1: a blunder view dropped from the fit, its track kept (its residual: to the track's point refitted without it)");
  std::ostringstream os;
  write_header(os, "rpc-residuals", 1, refs, meta,
               {"track", "image", "x", "y", "dx_before", "dy_before", "dx_after", "dy_after", "flagged", "sigma", "dropped"});
  for (size_t k = 0; k < r.obs_image.size(); ++k) {
    int t = r.obs_track[k];
    write_record(os, {static_cast<double>(tracks[t].id), static_cast<double>(r.obs_image[k] + 1), r.obs_xy[k][0],
                      r.obs_xy[k][1], r.res_before[k][0], r.res_before[k][1], r.res_after[k][0], r.res_after[k][1],
                      static_cast<double>(r.flagged[t]), r.obs_sigma[k], static_cast<double>(r.obs_dropped[k])});
  }
  long used = std::count(r.initial_ok.begin(), r.initial_ok.end(), 1);
  long flagged = std::count(r.flagged.begin(), r.flagged.end(), 1);
  os << "# tracks: " << used << '\n';
  os << "# tracks_not_intersected: " << static_cast<long>(tracks.size()) - used << '\n';
  os << "# tracks_by_length: " << format_lengths(tracks_by_length(tracks, r)) << '\n';
  os << "# observations: " << r.obs_image.size() << '\n';
  os << "# observations_with_sigma: " << r.obs_with_sigma << '\n';
  os << "# default_sigma_px: " << format_number(r.default_sigma_px) << '\n';
  os << "# reference_sigma_px: " << format_number(r.reference_sigma_px) << '\n';
  os << "# rms_before_px: " << format_number(residual_rms(r, false)) << '\n';
  os << "# rms_after_px: " << format_number(residual_rms(r, true)) << '\n';
  os << "# rms_after_unflagged_px: " << format_number(inlier_rms(r)) << '\n';
  os << "# sigma0_weighted: " << format_number(r.sigma0_weighted) << '\n';
  const std::vector<ImageReport> per = image_reports(images.size(), tracks, r);
  for (size_t i = 0; i < images.size(); ++i) {
    const std::string k = "# image" + std::to_string(i + 1);
    os << k << "_observations: " << per[i].observations << '\n';
    os << k << "_tracks_by_length: " << format_lengths(per[i].tracks_by_length) << '\n';
    os << k << "_median_sigma_px: " << format_number(per[i].median_sigma) << '\n';
    os << k << "_rms_before_px: " << format_number(per[i].rms_before) << '\n';
    os << k << "_rms_after_px: " << format_number(per[i].rms_after) << '\n';
    os << k << "_rms_after_unflagged_px: " << format_number(per[i].rms_after_unflagged) << '\n';
  }
  os << "# flagged_tracks: " << flagged << '\n';
  os << "# dropped_views: " << r.dropped_views << '\n';
  os << "# tracks_with_dropped_views: " << r.tracks_with_dropped << '\n';
  if (check_n > 0) {
    os << "# check_observations: " << check_n << '\n';
    os << "# check_rms_px: " << format_number(check_rms) << '\n';
  }
  os << "# iterations: " << r.iterations << '\n';
  write_file_atomic(path, os.str());
}

// The adjusted models: bias folded into a refitted RPC00B per image, as _rpc.txt and .RPB (and a TIFF copy).
std::vector<RpcFit> write_models(const Opts& o, const std::vector<AdjustImage>& images, const AdjustResult& r) {
  double h_lo = INFINITY, h_hi = -INFINITY;
  for (size_t t = 0; t < r.ground.size(); ++t)
    if (r.initial_ok[t]) {
      h_lo = std::min(h_lo, r.ground[t][2]);
      h_hi = std::max(h_hi, r.ground[t][2]);
    }
  // the refit covers the tracks' heights with a margin (and at least the models' own height range near them)
  const double margin = std::max(50.0, 0.25 * (h_hi - h_lo));
  h_lo -= margin;
  h_hi += margin;
  std::vector<RpcFit> fits(images.size());
  parallel_for(images.size(), o.threads, [&](size_t i) {
    try {
      fits[i] = fold_bias(images[i].model, r.bias[i], images[i].width, images[i].height, h_lo, h_hi);
    } catch (const NumericalError& e) {
      throw NumericalError(images[i].path + ": the adjusted model cannot be fitted: " + e.what());
    }
  });
  for (size_t i = 0; i < images.size(); ++i) {
    std::string stem = (fs::path(o.out) / fs::path(images[i].path).stem()).string();
    write_rpc_txt(stem + "_rpc.txt", fits[i].model);
    write_rpc_rpb(stem + ".RPB", fits[i].model);
    if (o.write_tiff) write_rpc_tiff_copy(images[i].path, (fs::path(o.out) / fs::path(images[i].path).filename()).string(), fits[i].model);
  }
  return fits;
}

void write_bias(const std::string& path, const Opts& o, const std::vector<AdjustImage>& images,
                const std::vector<RpcSource>& sources, const AdjustResult& r, const std::vector<RpcFit>& fits) {
  BiasTable bt;
  for (const auto& im : images) bt.images.push_back({im.path, im.width, im.height});
  meta_set(bt.meta, "model", o.model);
  meta_set(bt.meta, "bias", "observed pixel = model projection (x, y) + (a0 + a1 x + a2 y, b0 + b1 x + b2 y), pixels");
  for (size_t i = 0; i < images.size(); ++i) meta_set(bt.meta, "model" + std::to_string(i + 1), models_line(sources, i));
  meta_set(bt.meta, "solver", r.solver_report);
  bt.bias = r.bias;
  bt.extra_names = {"fixed", "refit_rms_px", "refit_max_px"};
  for (size_t i = 0; i < images.size(); ++i) bt.extra.push_back({images[i].fixed ? 1.0 : 0.0, fits[i].rms_px, fits[i].max_px});
  save_bias_table(path, bt);
}

// GCPs and check points evaluated on the delivered models (before) and the adjusted ones (after).
struct PointSet {
  const char* name;  // "control", "check"
  GcpRole role;
  const std::vector<AdjustControl>* points;
  ControlEvaluation before, after;
  AccuracyStats stats_before, stats_after;
};

// intersected minus known, ENU metres, per point (NaN where not intersected)
std::vector<Eigen::Vector3d> point_errors(const std::vector<AdjustControl>& p, const ControlEvaluation& e) {
  std::vector<Eigen::Vector3d> out;
  for (size_t k = 0; k < p.size(); ++k)
    out.push_back(e.intersection[k].ok ? enu_error(e.intersection[k].llh, p[k].llh) : Eigen::Vector3d::Constant(NAN));
  return out;
}

AccuracyStats set_stats(const std::vector<Eigen::Vector3d>& err) {
  std::vector<Eigen::Vector3d> ok;
  for (const auto& e : err)
    if (e.allFinite()) ok.push_back(e);
  return accuracy_stats(ok);
}

std::vector<PointSet> evaluate_sets(const std::vector<AdjustImage>& images, const AdjustResult& r,
                                    const std::vector<AdjustControl>& control, const std::vector<AdjustControl>& check) {
  std::vector<PointSet> sets = {{"control", GcpRole::control, &control, {}, {}, {}, {}},
                                {"check", GcpRole::check, &check, {}, {}, {}, {}}};
  for (auto& s : sets) {
    s.before = evaluate_controls(images, nullptr, *s.points);
    s.after = evaluate_controls(images, &r.bias, *s.points);
    s.stats_before = set_stats(point_errors(*s.points, s.before));
    s.stats_after = set_stats(point_errors(*s.points, s.after));
  }
  return sets;
}

// The accuracy file (tpkit-formats(5) accuracy): one record per image measurement of a point.
void write_accuracy(const std::string& path, const std::vector<AdjustImage>& images, const std::vector<PointSet>& sets) {
  std::vector<ImageRef> refs;
  for (const auto& im : images) refs.push_back({im.path, im.width, im.height});
  Meta meta;
  meta_set(meta, "role", "0: control point (in the fit), 1: check point (never in the fit)");
  meta_set(meta, "dx_after", "projection of the known ground position by the adjusted model minus the measurement (pixels; _before: delivered model)");
  meta_set(meta, "e_after", "the point intersected from its measurements on the adjusted models minus its known position, metres east, north, up "
                            "at the known position (_before: on the delivered models; nan: not intersected)");
  meta_set(meta, "ce90", "90th percentile of the horizontal error (nearest rank); ce90_normal = 1.5175 rmse_h, le90_normal = 1.6449 rmse_v");
  std::ostringstream os;
  write_header(os, "accuracy", 1, refs, meta,
               {"id", "role", "image", "x", "y", "sigma_px", "dx_before", "dy_before", "dx_after", "dy_after", "e_before", "n_before",
                "u_before", "e_after", "n_after", "u_after"});
  for (const auto& s : sets) {
    const auto eb = point_errors(*s.points, s.before), ea = point_errors(*s.points, s.after);
    for (size_t p = 0; p < s.points->size(); ++p) {
      const AdjustControl& c = (*s.points)[p];
      for (size_t k = 0; k < c.views.size(); ++k) {
        const Eigen::Vector2d db = s.before.known_residual_px[p][k], da = s.after.known_residual_px[p][k];
        write_record(os, {static_cast<double>(c.id), static_cast<double>(s.role), static_cast<double>(c.views[k].first + 1),
                          c.views[k].second[0], c.views[k].second[1], c.sigma_px[k], db[0], db[1], da[0], da[1], eb[p][0], eb[p][1],
                          eb[p][2], ea[p][0], ea[p][1], ea[p][2]});
      }
    }
  }
  for (const auto& s : sets)
    for (const auto& [phase, st] : {std::make_pair("before", &s.stats_before), std::make_pair("after", &s.stats_after)}) {
      const std::string k = std::string("# ") + s.name + "_" + phase + "_";
      os << k << "n: " << st->n << '\n';
      os << k << "rmse_h_m: " << format_number(st->rmse_r) << '\n';
      os << k << "rmse_v_m: " << format_number(st->rmse_u) << '\n';
      os << k << "rmse_e_m: " << format_number(st->rmse_e) << '\n';
      os << k << "rmse_n_m: " << format_number(st->rmse_n) << '\n';
      os << k << "mean_enu_m: " << format_number(st->mean[0]) << ' ' << format_number(st->mean[1]) << ' ' << format_number(st->mean[2]) << '\n';
      os << k << "ce90_m: " << format_number(st->ce90) << '\n';
      os << k << "le90_m: " << format_number(st->le90) << '\n';
      os << k << "ce90_normal_m: " << format_number(st->ce90_normal) << '\n';
      os << k << "le90_normal_m: " << format_number(st->le90_normal) << '\n';
    }
  write_file_atomic(path, os.str());
}

std::string stats_line(const AccuracyStats& s) {
  return "RMSE horizontal " + format_figure(s.rmse_r, 3) + " m, vertical " + format_figure(s.rmse_u, 3) + " m, CE90 " +
         format_figure(s.ce90, 3) + " m, LE90 " + format_figure(s.le90, 3) + " m";
}

int run(const Opts& o) {
  if (o.images.empty()) throw UsageError("no images given");
  if (o.tracks.empty()) throw UsageError("--tracks: at least one tracks file is needed");
  if (o.out.empty()) throw UsageError("-o DIR is required");
  {
    // '-' is standard input, which one reader takes whole
    std::vector<std::string> text_inputs = o.tracks;
    text_inputs.insert(text_inputs.end(), o.check.begin(), o.check.end());
    text_inputs.insert(text_inputs.end(), o.gcp.begin(), o.gcp.end());
    if (std::count(text_inputs.begin(), text_inputs.end(), "-") > 1)
      throw UsageError("'-' (standard input) is given more than once among --tracks, --check and --gcp: it can be read once");
  }
  const BiasModel model = parse_bias_model(o.model);
  parse_ground_crs(o.crs);
  if (o.threads < 1 || o.threads > kMaxThreads) throw UsageError("--threads must be between 1 and " + std::to_string(kMaxThreads));
  AdjustOptions ao;
  ao.model = model;
  ao.loss_px = o.loss;
  ao.flag_px = o.flag;
  ao.prior_shift_px = o.prior_shift;
  ao.prior_linear = o.prior_linear;
  ao.threads = o.threads;
  ao.max_iterations = o.iterations;
  ao.use_sigma = !o.unweighted;
  if (!std::isnan(o.default_sigma) && !(o.default_sigma > 0 && std::isfinite(o.default_sigma)))
    throw UsageError("--default-sigma: expected a positive number of pixels, got " + format_number(o.default_sigma));
  ao.default_sigma_px = o.default_sigma;
  ao.progress = isatty(2);
  if (!o.height_prior.empty() && !o.dem.empty()) throw UsageError("--height-prior and --dem exclude each other");
  if (!o.dem_datum.empty() && o.dem.empty()) throw UsageError("--dem-datum goes with --dem");
  if (!o.height_prior.empty()) ao.height = parse_height_prior(o.height_prior);
  if (!std::isnan(o.dem_sigma) && o.dem.empty()) throw UsageError("--dem-sigma goes with --dem");
  if (!o.dem.empty() && !std::isnan(o.dem_sigma) && o.dem_sigma < kMinHeightSigma)
    throw UsageError("--dem-sigma " + format_figure(o.dem_sigma) + ": below " + format_figure(kMinHeightSigma) + " m (no DEM is that good; the cost would overflow)");
  std::vector<RpcSource> sources;
  std::vector<AdjustImage> images = load_images(o, sources);
  if (!o.dem.empty()) {
    // without --dem-sigma the sigma is estimated from the data below (a placeholder until then)
    ao.height = reference_dem_prior(std::make_shared<const ReferenceDem>(o.dem, ReferenceDemOptions{o.dem_datum}),
                                    std::isnan(o.dem_sigma) ? 1.0 : o.dem_sigma);
  }
  const std::vector<AdjustTrack> tracks = gather_tracks(o.tracks, o.images);
  const std::vector<AdjustTrack> check = gather_tracks(o.check, o.images);
  const std::vector<Gcp> gcps = read_gcp_files(o.gcp);
  ao.control = gcps_to_adjust(gcps, GcpRole::control, images);
  const std::vector<AdjustControl> check_points = gcps_to_adjust(gcps, GcpRole::check, images);
  if (!o.gcp.empty() && ao.control.empty()) warn("--gcp: no control point (role 0) in the files: only check points, the fit is that without GCPs");

  create_output_dir(o.out);
  std::vector<std::string> inputs = o.images;
  inputs.insert(inputs.end(), o.tracks.begin(), o.tracks.end());
  inputs.insert(inputs.end(), o.check.begin(), o.check.end());
  inputs.insert(inputs.end(), o.gcp.begin(), o.gcp.end());
  if (!o.dem.empty()) inputs.push_back(o.dem);
  for (const auto& s : sources) inputs.push_back(s.path);  // the models read (a sidecar, an --rpc file)
  const fs::path dir(o.out);
  std::vector<std::pair<std::string, std::string>> outputs;
  for (const char* name : {"rpc.bias", "ground.points", "ground.geojson", "ground.csv", "ground.csvt", "ground.prj",
                           "rpc.residuals", "accuracy", "residuals.svg"})
    outputs.push_back({"-o", (dir / name).string()});
  // the adjusted models (write_models' names): an image's own sidecar in -o is an input, refused here
  // rather than after the adjustment
  for (const auto& im : images) {
    const std::string stem = (dir / fs::path(im.path).stem()).string();
    outputs.push_back({"-o", stem + "_rpc.txt"});
    outputs.push_back({"-o", stem + ".RPB"});
    if (o.write_tiff) outputs.push_back({"--write-tiff", (dir / fs::path(im.path).filename()).string()});
  }
  check_outputs(outputs, inputs);

  if (!gcps.empty()) {
    // GCPs wrong together (a zone, a datum, geoid heights) move the whole block and agree with the tie
    // points after the fit: only the delivered models can tell, so they judge the GCPs first
    std::vector<AdjustControl> all = ao.control;
    all.insert(all.end(), check_points.begin(), check_points.end());
    const GcpModelCheck mc = check_gcps_on_models(images, all);
    std::string what = "--gcp";
    for (const auto& f : o.gcp) what += " " + f;
    if (mc.refuse && !o.force_gcp)
      throw NumericalError(what + ": " + mc.problem + ": " + mc.figures + " (--force-gcp adjusts with them all the same)");
    if (!mc.problem.empty() && o.strict) throw NumericalError(what + ": " + mc.problem + " (--strict): " + mc.figures);
    if (!mc.problem.empty())
      warn(what + ": " + mc.problem + ": " + mc.figures + " (--strict makes this an error)");
    else
      std::cerr << "rpc-adjust: " << what << ": on the delivered models: " << mc.figures << "\n";
  }

  // A height prior is judged against the fit without it (check_height_prior), solved first: the DEM's
  // sigma, where none is given, is its spread about that fit's points (estimated_height_sigma).
  std::unique_ptr<AdjustResult> free_fit;
  const std::string prior_name = !o.height_prior.empty() ? "--height-prior " + o.height_prior : "--dem " + o.dem;
  if (ao.height.at) {
    AdjustOptions free_options = ao;
    free_options.height = HeightPrior{};
    free_options.keep_untrusted = false;  // a free fit that fails: the models or the tracks are wrong
    free_fit = std::make_unique<AdjustResult>(adjust_rpcs(images, tracks, free_options));
    // the prior weighs against the tie points' actual precision (HeightPrior::tie_sigma0)
    ao.height.tie_sigma0 = free_fit->sigma0_weighted;
    const HeightPriorSpread sp = height_prior_spread(ao.height, *free_fit);
    const std::string spread = "prior minus free height over " + std::to_string(sp.covered) + " tracks: median " +
                               format_figure(sp.median_dh) + " m, NMAD " + format_figure(sp.nmad_dh) + " m";
    std::cerr << "rpc-adjust: " << prior_name << ": weighed against the tie points' a posteriori sigma0 "
              << format_figure(free_fit->sigma0_weighted) << " (weighted, px at the reference sigma " << format_figure(free_fit->reference_sigma_px)
              << " px; the fit without it, " << free_fit->iterations << " iterations)\n";
    if (!o.dem.empty() && std::isnan(o.dem_sigma)) {
      ao.height.sigma = estimated_height_sigma(sp);
      std::cerr << "rpc-adjust: --dem " << o.dem << ": sigma " << format_figure(ao.height.sigma) << " m estimated from the data (" << spread
                << "; floored at " << format_figure(kPriorPrecisionRatio) << " times the points' median height precision " << format_figure(sp.median_sigma_h) << " m and "
                << format_figure(kMinEstimatedHeightSigma) << " m; --dem-sigma sets it)\n";
    } else if (std::isfinite(sp.nmad_dh) && sp.nmad_dh > 3 * ao.height.sigma) {
      warn(prior_name + ": its sigma " + format_figure(ao.height.sigma) + " m is far below its spread about the tie points (" + spread +
           "): it pulls the points to heights they do not have (leave --dem-sigma out to estimate it)");
    }
  }
  // a fit that fails with a height prior or GCPs is held until the checks below have said whether they made it fail
  ao.keep_untrusted = ao.height.at || !ao.control.empty();
  AdjustResult r = adjust_rpcs(images, tracks, ao);
  const FitTrust trust = fit_trust(images, tracks, r, ao.flag_px);
  if (ao.height.at) {
    // a prior that contradicts the tie points degrades the fit silently: compared with the fit without it
    const HeightPriorCheck pc = check_height_prior(images, tracks, ao, r, free_fit.get());
    const std::string& what = prior_name;
    if (pc.impossible)
      throw NumericalError(what + " contradicts the tie points: " + pc.figures + "; the biases it forces are beyond any delivered model's (" +
                           format_figure(pc.forced_bias_px) + " px on image" + std::to_string(pc.forced_image + 1) + "): a wrong height or vertical datum?");
    if (pc.contradicts && !trust.ok())
      throw NumericalError(what + " contradicts the tie points: " + pc.figures + "; the fit with it fails: " + trust.figures);
    if (pc.contradicts && o.strict)
      throw NumericalError(what + " contradicts the tie points (--strict): " + pc.figures);
    if (pc.contradicts)
      warn(what + " contradicts the tie points: " + pc.figures + " (check its value and datum, or drop it; --strict makes this an error)");
    else
      std::cerr << "rpc-adjust: " << what << " agrees with the tie points: " << pc.figures << "\n";
    if (!pc.contradicts && pc.forced_bias_px > kPriorWarnBiasPx)
      warn(what + " moves the model of image" + std::to_string(pc.forced_image + 1) + " " + images[static_cast<size_t>(pc.forced_image)].path +
           " by " + format_figure(pc.forced_bias_px) + " px (its level " + format_figure(pc.median_dh) + " m from the fit without it): more than most delivered models are off (" +
           format_figure(kPriorWarnBiasPx) + " px); a DEM over another vertical datum does so too: check its datum");
  }
  if (!ao.control.empty()) {
    // GCPs that contradict the tie points (or each other): solved again without them, compared
    const GcpCheck gc = check_gcps(images, tracks, ao, r);
    if (gc.contradicts && !trust.ok())
      throw NumericalError("--gcp: the control points contradict the tie points: " + gc.figures + "; the fit with them fails: " + trust.figures);
    if (gc.contradicts && o.strict) throw NumericalError("--gcp: the control points contradict the tie points (--strict): " + gc.figures);
    if (gc.contradicts)
      warn("--gcp: the control points contradict the tie points: " + gc.figures + " (check that point's coordinates, datum and measurements; --strict makes this an error)");
    else
      std::cerr << "rpc-adjust: --gcp: the control points agree with the tie points: " << gc.figures << "\n";
  }
  if (!trust.ok()) throw NumericalError(trust.message());
  std::vector<PointSet> sets;
  if (!gcps.empty()) sets = evaluate_sets(images, r, ao.control, check_points);
  long check_n = 0;
  double check_rms = check.empty() ? NAN : held_out_rms(images, r.bias, check, &check_n);
  auto fits = write_models(o, images, r);
  write_bias((dir / "rpc.bias").string(), o, images, sources, r, fits);
  write_points(dir, o, images, sources, tracks, r);
  write_residuals((dir / "rpc.residuals").string(), images, tracks, r, check_rms, check_n);
  if (!sets.empty()) write_accuracy((dir / "accuracy").string(), images, sets);
  plot_rpc_residuals((dir / "residuals.svg").string(), images, r,
                     "rpc-adjust --model " + o.model + ": residual fields before (zero bias) and after, projected minus observed");

  long flagged = std::count(r.flagged.begin(), r.flagged.end(), 1);
  long used = std::count(r.initial_ok.begin(), r.initial_ok.end(), 1);
  std::cerr << "rpc-adjust: " << used << " tracks, " << r.obs_image.size() << " observations, model " << o.model
            << ": rms " << format_figure(residual_rms(r, false)) << " px before, " << format_figure(residual_rms(r, true)) << " px after";
  if (flagged > 0) std::cerr << " (" << format_figure(inlier_rms(r)) << " px without the " << flagged << " flagged tracks)";
  if (check_n > 0) std::cerr << ", held-out " << format_figure(check_rms) << " px (" << check_n << " observations)";
  std::cerr << "; " << r.iterations << " iterations\n";
  if (!r.converged)
    warn("the solver stopped before it converged (" + r.solver_report + "); a larger --iterations may change the models");
  std::cerr << "rpc-adjust: tracks by length " << format_lengths(tracks_by_length(tracks, r)) << "; ";
  if (r.obs_with_sigma == 0)
    std::cerr << "unit weights (" << (o.unweighted ? "--unweighted" : "no sigma given") << ")\n";
  else
    std::cerr << r.obs_with_sigma << " observations weighted by their sigma, " << r.obs_image.size() - r.obs_with_sigma
              << " at " << format_figure(r.default_sigma_px) << " px; weights reference sigma " << format_figure(r.reference_sigma_px)
              << " px / sigma, weighted sigma0 " << format_figure(r.sigma0_weighted) << " px\n";
  const std::vector<ImageReport> per = image_reports(images.size(), tracks, r);
  for (size_t i = 0; i < images.size(); ++i)
    std::cerr << "rpc-adjust: image" << i + 1 << " " << images[i].path << (images[i].fixed ? " (fixed)" : "") << ": "
              << per[i].observations << " observations, tracks by length " << format_lengths(per[i].tracks_by_length)
              << ", median sigma " << format_figure(per[i].median_sigma) << " px, rms " << format_figure(per[i].rms_before)
              << " px before, " << format_figure(per[i].rms_after) << " px after"
              << (flagged > 0 ? " (" + format_figure(per[i].rms_after_unflagged) + " px without flagged tracks)" : std::string()) << "\n";
  if (r.obs_with_sigma > 0 && r.obs_with_sigma < static_cast<long>(r.obs_image.size()) && std::isnan(o.default_sigma))
    warn(std::to_string(r.obs_image.size() - r.obs_with_sigma) + " observations have no sigma: weighted as the median of the others, " +
         format_figure(r.default_sigma_px) + " px (--default-sigma sets it, --unweighted ignores every sigma)");
  for (const auto& s : sets) {
    if (s.points->empty()) continue;
    std::cerr << "rpc-adjust: " << s.name << " points (" << s.stats_after.n << " of " << s.points->size() << " intersected): before "
              << stats_line(s.stats_before) << "; after " << stats_line(s.stats_after) << "\n";
  }
  double worst_refit = 0;
  for (const auto& f : fits) worst_refit = std::max(worst_refit, f.max_px);
  std::cerr << "rpc-adjust: adjusted models refitted to the biased ones within " << format_figure(worst_refit, 3) << " px\n";
  if (used < static_cast<long>(tracks.size()))
    warn(std::to_string(tracks.size() - used) + " tracks could not be intersected with the delivered models (left out)");
  if (r.dropped_views > 0) {
    long saved = 0;
    for (size_t t = 0; t < r.views_dropped.size(); ++t) saved += r.views_dropped[t] > 0 && !r.flagged[t];
    std::cerr << "rpc-adjust: " << r.dropped_views << " views dropped as blunders from " << r.tracks_with_dropped
              << " tracks of 3 or more views (" << saved << " of them kept: their other views fit under --flag; "
              << r.drop_rounds << " refits; column dropped of rpc.residuals)\n";
  }
  if (flagged > 0)
    warn(std::to_string(flagged) + " tracks keep an RMS residual above --flag " + format_figure(o.flag) +
         " px after the robust fit (flagged in ground.points and rpc.residuals)");
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "rpc-adjust", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("images", o->images, "the images (their RPCs: tag 50844 or a sidecar beside them)");
        app.add_option("--tracks", o->tracks, "tracks or matches files (tracks of any length >= 2; a match is a 2-view track)");
        app.add_option("--check", o->check, "held-out tracks files: evaluated, not used in the fit");
        app.add_option("--model", o->model, "bias model: shift, drift or affine");
        app.add_option("--fixed", o->fixed, "an image whose model is kept (repeatable)")
            ->allow_extra_args(false);  // one image each: `--fixed A B C` leaves B and C to the images
        app.add_option("--gcp", o->gcp, "ground control and check points: ASP .gcp or tpkit gcp files")->allow_extra_args(false);
        app.add_option("--rpc", o->rpc, "IMAGE=FILE: the RPC model of IMAGE from FILE (repeatable)");
        app.add_option("--height-prior", o->height_prior, "H+-S: height prior of every ground point (m)");
        app.add_option("--dem", o->dem, "GeoTIFF DEM (any CRS; m above --dem-datum): height prior");
        app.add_option("--dem-datum", o->dem_datum, "the DEM's heights: ellipsoid | egm96 | egm2008 | a PROJ vertical grid file (default: the DEM's vertical GeoTIFF keys, ellipsoid without them)");
        app.add_option("--dem-sigma", o->dem_sigma, "sigma of the DEM heights (m; default: estimated from the data, said on stderr)")->check(Positive);
        app.add_option("--crs", o->crs, "ground.points coordinates: geographic, utm or ecef");
        app.add_option("--loss", o->loss, "Huber loss scale (px)")->check(Positive);
        app.add_flag("--unweighted", o->unweighted, "ignore the observations' sigmas (every one at --default-sigma, else 1 px)");
        app.add_option("--default-sigma", o->default_sigma, "sigma of observations without one (px; default: median of those given, else 1)");
        app.add_option("--flag", o->flag, "flag tracks whose RMS after the fit exceeds this (px)")->check(Positive);
        app.add_option("--prior-shift", o->prior_shift, "sigma of the shift terms' prior (px)")->check(Positive);
        app.add_option("--prior-linear", o->prior_linear, "sigma of the linear terms' prior (px per px)")->check(Positive);
        app.add_option("--iterations", o->iterations, "largest number of solver iterations")->check(Positive);
        app.add_option("--threads", o->threads, "threads");
        app.add_flag("--strict", o->strict, "a height prior (--height-prior, --dem) or GCPs (--gcp) that contradict the tie points are an error");
        app.add_flag("--force-gcp", o->force_gcp, "adjust with GCPs that lie more than 150 px (median) from the delivered models' projections");
        app.add_flag("--write-tiff", o->write_tiff, "also write a copy of each image with the adjusted tag 50844");
        app.add_option("-o,--out", o->out, "output folder (created if needed)");
        return [o]() { return run(*o); };
      },
      tpkit_man_page);
}
