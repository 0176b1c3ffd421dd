// tp-ground: ground coordinates of tie-point tracks from the images' RPC models (man/tp-ground.1).
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/parallel_for.hpp"
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
};

int run(const Opts& o) {
  if (o.images.size() < 2) throw UsageError("at least two images are needed");
  if (o.tracks.empty()) throw UsageError("--tracks: at least one tracks file is needed");
  if (o.threads < 1 || o.threads > kMaxThreads) throw UsageError("--threads must be between 1 and " + std::to_string(kMaxThreads));
  const GroundCrs crs = parse_ground_crs(o.crs);
  std::vector<std::string> inputs = o.images;
  inputs.insert(inputs.end(), o.tracks.begin(), o.tracks.end());
  check_outputs({{"-o", o.output}}, inputs);
  auto overrides = parse_rpc_overrides(o.rpc);
  std::vector<RpcSource> src;
  std::vector<ImageRef> refs;
  for (const auto& im : o.images) {
    ImageInfo info = image_info(im);
    refs.push_back({im, info.width, info.height});
    src.push_back(load_image_rpc(im, overrides));
  }
  const auto tracks = gather_tracks(o.tracks, o.images);
  if (tracks.empty()) throw InputError(o.tracks[0], 0, "no tracks");
  std::vector<RpcIntersection> x(tracks.size());
  parallel_for(tracks.size(), o.threads, [&](size_t t) {
    std::vector<RpcObservation> v;
    for (const auto& [i, xy] : tracks[t].views) v.push_back({&src[i].model, nullptr, xy});
    x[t] = intersect_rpc(v);
  });
  double sum = 0;
  long n = 0, failed = 0;
  for (size_t t = 0; t < tracks.size(); ++t) {
    if (!x[t].ok) {
      ++failed;
      continue;
    }
    sum += x[t].rms_px * x[t].rms_px * tracks[t].views.size();
    n += static_cast<long>(tracks[t].views.size());
  }
  if (n == 0) throw NumericalError("no track could be intersected with the images' RPCs (do they overlap?)");
  const double sigma0 = std::sqrt(sum / (2.0 * n));
  GroundConverter conv(crs, src[0].model.lon_off, src[0].model.lat_off);
  Meta meta;
  meta_set(meta, "crs", conv.description());
  for (size_t i = 0; i < src.size(); ++i)
    meta_set(meta, "model" + std::to_string(i + 1), src[i].path + " (" + rpc_form_name(src[i].form) + ")");
  meta_set(meta, "method", "least squares over all views of each track (Gauss-Newton on the RPC projections)");
  meta_set(meta, "rms_px", "RMS over the track's views of the residual, projected minus observed (pixels)");
  meta_set(meta, "sigma_h", "standard deviation of h (m) for the image noise sigma0 = " + format_number(sigma0) +
                                " px (per coordinate, from all residuals)");
  std::vector<std::string> cols = {"track"};
  for (const auto& c : conv.columns()) cols.push_back(c);
  cols.insert(cols.end(), {"sigma_h", "views", "rms_px"});
  std::ostringstream os;
  write_header(os, "ground", 1, refs, meta, cols);
  for (size_t t = 0; t < tracks.size(); ++t) {
    if (!x[t].ok) continue;
    Eigen::Vector3d c = conv(x[t].llh);
    write_record(os, {static_cast<double>(tracks[t].id), c[0], c[1], c[2], x[t].sigma_h1 * sigma0,
                      static_cast<double>(tracks[t].views.size()), x[t].rms_px});
  }
  os << "# points: " << tracks.size() - failed << '\n';
  os << "# rms_px: " << format_number(std::sqrt(sum / n)) << '\n';
  write_file_atomic(o.output, os.str());
  std::cerr << "tp-ground: " << tracks.size() - failed << " ground points, residual rms " << std::sqrt(sum / n) << " px\n";
  if (failed) warn(std::to_string(failed) + " tracks could not be intersected (left out)");
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-ground", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("images", o->images, "the images (their RPCs: tag 50844 or a sidecar beside them)");
        app.add_option("--tracks", o->tracks, "tracks files (any number of views >= 2 each)");
        app.add_option("--rpc", o->rpc, "IMAGE=FILE: the RPC model of IMAGE from FILE (repeatable)");
        app.add_option("--crs", o->crs, "output coordinates: geographic, utm or ecef");
        app.add_option("--threads", o->threads, "threads");
        app.add_option("-o,--output", o->output, "ground file, - for stdout");
        return [o]() { return run(*o); };
      },
      tpkit_man_page);
}
