// tp-ground: ground coordinates of tie-point tracks from the images' RPC models (man/tp-ground.1).
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/rpc/ground_export.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_ground.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tool_support.hpp"

extern const char* const tpkit_man_page;

namespace {
using namespace tpkit;

struct Opts {
  std::vector<std::string> images, tracks, rpc;
  std::string crs = "geographic", output = "-";
  int threads = 1;
  double flag = 2;
};

int run(const Opts& o) {
  if (o.images.size() < 2) throw UsageError("at least two images are needed");
  if (o.tracks.empty()) throw UsageError("--tracks: at least one tracks file is needed");
  if (o.threads < 1 || o.threads > kMaxThreads) throw UsageError("--threads must be between 1 and " + std::to_string(kMaxThreads));
  const GroundCrs crs = parse_ground_crs(o.crs);
  std::vector<std::string> inputs = o.images;
  inputs.insert(inputs.end(), o.tracks.begin(), o.tracks.end());
  std::vector<std::pair<std::string, std::string>> outputs;
  for (const auto& f : ground_output_files(o.output)) outputs.push_back({"-o", f});
  check_outputs(outputs, inputs);
  auto overrides = parse_rpc_overrides(o.rpc);
  check_rpc_overrides(overrides, o.images);
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
    table.points.push_back({tracks[t].id, x.llh,
                            {x.sigma_h1 * sigma0, static_cast<double>(tracks[t].views.size()), x.rms_px,
                             static_cast<double>(g.flags[t])}});
  }
  table.summary = {{"points", std::to_string(g.intersected)},
                   {"rms_px", format_number(g.rms_px)},
                   {"flagged_residual", std::to_string(g.residual_flagged)},
                   {"flagged_outside_box", std::to_string(g.outside_box)}};
  write_ground(o.output, table, conv);
  std::cerr << "tp-ground: " << g.intersected << " ground points, residual rms " << g.rms_px << " px\n";
  const long failed = static_cast<long>(tracks.size()) - g.intersected;
  if (failed) warn(std::to_string(failed) + " tracks could not be intersected (left out)");
  if (g.residual_flagged)
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
        app.add_option("--flag", o->flag, "flag tracks whose RMS residual exceeds this (px); most above it: refused")
            ->check(Positive);
        app.add_option("-o,--output", o->output, "ground file, - for stdout; .geojson/.json: GeoJSON, .csv: CSV (+ .csvt, .prj)");
        return [o]() { return run(*o); };
      },
      tpkit_man_page);
}
