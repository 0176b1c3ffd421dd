// tp-ground: ground coordinates of tie-point tracks from the images' RPC models (man/tp-ground.1).
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/ground/dem_align.hpp"
#include "tpkit/rpc/ground_export.hpp"
#include "tpkit/rpc/rpc_ground_shift.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_ground.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tool_support.hpp"

extern const char* const tpkit_man_page;

namespace {
namespace fs = std::filesystem;
using namespace tpkit;

struct Opts {
  std::vector<std::string> images, tracks, rpc;
  std::string crs = "geographic", output = "-";
  std::string compare, align, dem_datum, dz, models;
  int threads = 1;
  double flag = 2;
};

// The reference DEM stage (--compare, --align): dz before (and after) on stderr and in --dz; with --align the
// points are moved by the shift found and the models shifted by it written to --models.
struct DemStage {
  bool aligned = false;
  GroundShift shift;
};
DemStage dem_stage(const Opts& o, const std::vector<AdjustImage>& images, const std::vector<RpcSource>& src,
                   std::vector<GroundSample>& points) {
  DemStage st;
  const std::string& path = o.align.empty() ? o.compare : o.align;
  ReferenceDem dem(path, {o.dem_datum});
  DzReport report;
  meta_set(report.meta, "dem", path + " (" + dem.crs() + ", posting " + format_figure(dem.posting_m()) + " m, heights above " + dem.datum() +
                                  (dem.vertical_unit_m() != 1 ? " in units of " + format_figure(dem.vertical_unit_m()) + " m" : "") + ")");
  meta_set(report.meta, "dz", "h - DEM, m above the WGS 84 ellipsoid; NMAD = 1.4826 median|dz - median|; class 0: all points, 1..5: DEM slope classes (deg)");
  if (o.compare.size()) {
    report.stages.push_back(compare_to_dem(points, dem));
    std::cerr << describe_dem_comparison(report.stages[0], "tp-ground: dz ");
  } else {
    const DemAlignment a = align_to_dem(points, dem);
    st.aligned = true;
    st.shift = a.shift;
    report.stages = {a.before, a.after};
    const std::string shift = format_figure(a.shift.east) + " " + format_figure(a.shift.north) + " " + format_figure(a.shift.up);
    meta_set(report.meta, "shift_enu_m", shift);
    meta_set(report.meta, "shift_centre", format_number(a.shift.lon0) + " " + format_number(a.shift.lat0));
    meta_set(report.meta, "method", "Nuth & Kaab (2011), " + std::to_string(a.iterations) + " iterations" + (a.converged ? "" : " (not converged)"));
    std::cerr << describe_dem_comparison(a.before, "tp-ground: before alignment, dz ")
              << describe_dem_comparison(a.after, "tp-ground: after alignment, dz ")
              << "tp-ground: shift east north up " << shift << " m (" << a.iterations << " iterations, " << a.used << " points in the fit)\n";
    meta_set(report.meta, "tilt_after", format_figure(a.tilt.east_per_km) + " " + format_figure(a.tilt.north_per_km) +
                                            " m/km east north, span " + format_figure(a.tilt.range_m) + " m over the points, NMAD about it " + format_figure(a.tilt.nmad_m) + " m");
    if (a.tilt.significant())
      warn("dz after alignment is tilted (" + format_figure(a.tilt.east_per_km) + " m/km east, " + format_figure(a.tilt.north_per_km) +
           " m/km north: a span of " + format_figure(a.tilt.range_m) + " m over the points, against " + format_figure(a.tilt.nmad_m) +
           " m NMAD about the plane): a shift cannot remove a tilt, and on slopes the tilt pulls the horizontal shift; adjust with the DEM as a height prior (rpc-adjust --dem) or with GCPs, then align");
    if (!a.converged) warn("the alignment did not converge in " + std::to_string(a.iterations) + " iterations: its shift is not to be trusted");
    for (GroundSample& p : points) p = a.shift.apply(p);
    for (size_t i = 0; i < images.size() && !o.models.empty(); ++i) {
      const std::string stem = (fs::path(o.models) / fs::path(images[i].path).stem()).string();
      write_rpc_txt(stem + "_rpc.txt", shift_rpc_on_ground(src[i].model, a.shift));
    }
  }
  if (!o.dz.empty()) {
    std::ostringstream os;
    write_dem_dz(os, report);
    write_file_atomic(o.dz, os.str());
  }
  return st;
}

int run(const Opts& o) {
  if (o.images.size() < 2) throw UsageError("at least two images are needed");
  if (o.tracks.empty()) throw UsageError("--tracks: at least one tracks file is needed");
  if (o.threads < 1 || o.threads > kMaxThreads) throw UsageError("--threads must be between 1 and " + std::to_string(kMaxThreads));
  const GroundCrs crs = parse_ground_crs(o.crs);
  if (!o.compare.empty() && !o.align.empty()) throw UsageError("--compare and --align exclude each other");
  if (o.compare.empty() && o.align.empty() && (!o.dem_datum.empty() || !o.dz.empty()))
    throw UsageError("--dem-datum and --dz go with --compare or --align");
  if (!o.models.empty() && o.align.empty()) throw UsageError("--models goes with --align");
  std::vector<std::string> inputs = o.images;
  inputs.insert(inputs.end(), o.tracks.begin(), o.tracks.end());
  std::vector<std::pair<std::string, std::string>> outputs;
  for (const auto& f : ground_output_files(o.output)) outputs.push_back({"-o", f});
  if (!o.compare.empty()) inputs.push_back(o.compare);
  if (!o.align.empty()) inputs.push_back(o.align);
  if (!o.dz.empty()) outputs.push_back({"--dz", o.dz});
  if (!o.models.empty()) {
    create_output_dir(o.models);  // removed again if the run fails
    for (const auto& im : o.images) outputs.push_back({"--models", (fs::path(o.models) / fs::path(im).stem()).string() + "_rpc.txt"});
  }
  check_outputs(outputs, inputs);
  const auto overrides = resolve_rpc_overrides(parse_rpc_overrides(o.rpc), o.images);
  std::vector<RpcSource> src;
  std::vector<ImageRef> refs;
  std::vector<AdjustImage> images;
  for (const auto& im : o.images) {
    ImageInfo info = image_info(im);
    refs.push_back({im, info.width, info.height});
    src.push_back(load_image_rpc(im, overrides));
    images.push_back({im, info.width, info.height, src.back().model, false});
  }
  const auto tracks = gather_tracks(o.tracks, o.images);
  if (tracks.empty()) throw InputError(o.tracks[0], 0, "no tracks");
  check_tracks(images, tracks);
  const GroundSolution g = ground_points(images, tracks, {o.flag, o.threads});
  const double sigma0 = g.sigma0;
  std::vector<GroundSample> samples;
  for (size_t t = 0; t < tracks.size(); ++t)
    if (g.points[t].ok && g.flags[t] == 0) samples.push_back({g.points[t].llh[0], g.points[t].llh[1], g.points[t].llh[2]});
  DemStage dem;
  if (!o.compare.empty() || !o.align.empty()) dem = dem_stage(o, images, src, samples);
  GroundConverter conv(crs, src[0].model.lon_off, src[0].model.lat_off);
  GroundTable table;
  table.images = refs;
  Meta& meta = table.meta;
  for (size_t i = 0; i < src.size(); ++i)
    meta_set(meta, "model" + std::to_string(i + 1), src[i].path + " (" + rpc_form_name(src[i].form) + ")");
  meta_set(meta, "method", "least squares over all views of each track (Gauss-Newton on the RPC projections)");
  meta_set(meta, "rms_px", "RMS over the track's views of the residual, projected minus observed (pixels)");
  meta_set(meta, "sigma_h", "standard deviation of h (m) for the image noise sigma0 = " + format_number(sigma0) +
                                " px (per coordinate, from all residuals)");
  meta_set(meta, "flagged", "bits: 1 rms_px above --flag " + format_number(o.flag) +
                                " px, 2 outside a model's validity box (normalized coordinate beyond 1.1)");
  table.columns = {{"sigma_h", false}, {"views", true}, {"rms_px", false}, {"flagged", true}};
  for (size_t t = 0; t < tracks.size(); ++t) {
    const RpcIntersection& x = g.points[t];
    if (!x.ok) continue;
    Eigen::Vector3d llh = x.llh;
    if (dem.aligned) {
      const GroundSample p = dem.shift.apply({llh[0], llh[1], llh[2]});
      llh = Eigen::Vector3d(p.lon, p.lat, p.h);
    }
    table.points.push_back({tracks[t].id, llh,
                            {x.sigma_h1 * sigma0, static_cast<double>(tracks[t].views.size()), x.rms_px,
                             static_cast<double>(g.flags[t])}});
  }
  table.summary = {{"points", std::to_string(g.intersected)},
                   {"rms_px", format_number(g.rms_px)},
                   {"flagged_residual", std::to_string(g.residual_flagged)},
                   {"flagged_outside_box", std::to_string(g.outside_box)}};
  write_ground(o.output, table, conv);
  std::ostringstream line;
  line << g.intersected << " ground points, residual rms " << g.rms_px << " px";
  summary(line.str());  // printed once the outputs are committed
  const long failed = static_cast<long>(tracks.size()) - g.intersected;
  if (failed) warn(std::to_string(failed) + " tracks could not be intersected (left out)");
  if (g.biased)
    warn(g.warning);
  else if (g.residual_flagged)
    warn(std::to_string(g.residual_flagged) + " tracks have an RMS residual above --flag " + format_number(o.flag) + " px (flagged 1)");
  if (g.outside_box)
    warn(std::to_string(g.outside_box) + " points lie outside the models' validity box (flagged 2): their coordinates are extrapolated");
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-ground", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("images", o->images, "the images (their RPCs: tag 50844 or a sidecar beside them)");
        app.add_option("--tracks", o->tracks, "tracks or matches files (tracks of any length >= 2; a match is a 2-view track)");
        app.add_option("--rpc", o->rpc, "IMAGE=FILE: the RPC model of IMAGE from FILE (repeatable)");
        app.add_option("--crs", o->crs, "output coordinates: geographic, utm or ecef");
        app.add_option("--threads", o->threads, "threads");
        app.add_option("--flag", o->flag, "flag tracks whose RMS residual exceeds this (px); most above it and no bias of the models explains them: refused")
            ->check(Positive);
        app.add_option("--compare", o->compare, "reference DEM (GeoTIFF, any CRS): dz = h - DEM statistics, by slope class");
        app.add_option("--align", o->align, "reference DEM: the 3-D shift of the ground points onto it (Nuth & Kaab); -o writes the points moved");
        app.add_option("--dem-datum", o->dem_datum, "the DEM's heights: ellipsoid | egm96 | egm2008 | a PROJ vertical grid file (default: the DEM's vertical GeoTIFF keys, ellipsoid without them)");
        app.add_option("--dz", o->dz, "with --compare/--align: the dz statistics as a dem-dz file");
        app.add_option("--models", o->models, "with --align: folder for the shifted models (IMAGE-STEM_rpc.txt)");
        app.add_option("-o,--output", o->output, "ground file, - for stdout; .geojson/.json: GeoJSON, .csv: CSV (+ .csvt, .prj)");
        return [o]() { return run(*o); };
      },
      tpkit_man_page);
}
