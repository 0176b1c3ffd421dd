// reproj-eval: reprojection errors of tracks under a trifocal tensor, and trifocal point transfer
// (man/reproj-eval.1).
#include <iostream>
#include <memory>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/geometry/reproj_eval.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/geometry/trifocal_transfer.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::vector<std::string> files;
  std::string check, plot, output = "-";
  bool transfer = false;
};

void write_stats(std::ostream& os, const std::string& prefix, const tpkit::ReprojectionStats& s) {
  using tpkit::format_number;
  os << "# " << prefix << "n: " << s.n << '\n';
  os << "# " << prefix << "rmse_px: " << format_number(s.rmse) << '\n';
  for (int v = 0; v < 3; ++v) os << "# " << prefix << "rmse_view" << v + 1 << "_px: " << format_number(s.rmse_view[v]) << '\n';
  os << "# " << prefix << "median_px: " << format_number(s.median) << '\n';
  os << "# " << prefix << "max_px: " << format_number(s.max) << '\n';
}

std::string brief(const tpkit::ReprojectionStats& s) {
  std::ostringstream os;
  os.precision(4);
  os << s.n << " tracks, rmse " << s.rmse << " px (views " << s.rmse_view[0] << ", " << s.rmse_view[1] << ", "
     << s.rmse_view[2] << "), median " << s.median << ", max " << s.max;
  return os.str();
}

const tpkit::Tracks three_view_tracks(const std::string& path) {
  size_t left_out = 0;
  tpkit::Tracks t = tpkit::read_tracks_seen_in_all_views(path, 3, &left_out);
  if (left_out)
    tpkit::warn(t.source + ": " + std::to_string(left_out) + " tracks not seen in all three views left out; evaluating the " +
                std::to_string(t.size()) + " that are");
  return t;
}

int run_transfer(const Opts& o) {
  using namespace tpkit;
  if (o.files.empty() || o.files.size() > 2) throw UsageError("--transfer takes TRIFOCAL [PAIRS|-]");
  if (!o.check.empty() || !o.plot.empty()) throw UsageError("--check and --plot do not go with --transfer");
  const Trifocal tf = read_trifocal(o.files[0]);
  const Matches pairs = read_matches(o.files.size() == 2 ? o.files[1] : "-");
  Eigen::MatrixXd x3;
  try {
    x3 = transfer_point_line_point(tf.T, pairs.xy);
  } catch (const NumericalError& e) {
    throw NumericalError(pairs.source + ": " + e.what());
  }
  Points out;
  if (tf.images.size() == 3) out.images = {tf.images[2]};
  meta_set(out.meta, "transfer", "view 3 from views 1 and 2 of " + tf.source + " (point-line-point)");
  out.xy = x3;
  out.extra.values.resize(x3.rows(), 0);
  save_points(o.output, out);
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "reproj-eval", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("files", o->files, "TRIFOCAL TRACKS, or with --transfer TRIFOCAL [PAIRS]");
        app.add_option("--check", o->check, "held-out tracks to evaluate as well");
        app.add_option("--plot", o->plot, "SVG figure of the error distribution");
        app.add_flag("--transfer", o->transfer, "transfer view-1/view-2 pairs to view 3");
        app.add_option("-o,--output", o->output, "output file, - for stdout");
        return [o]() -> int {
          using namespace tpkit;
          std::vector<std::string> inputs = o->files;
          inputs.push_back(o->check);
          check_outputs({{"-o", o->output}, {"--plot", o->plot}}, inputs);
          if (o->transfer) return run_transfer(*o);
          if (o->files.size() != 2) throw UsageError("expected TRIFOCAL TRACKS");
          const Trifocal tf = read_trifocal(o->files[0]);
          const Tracks tracks = three_view_tracks(o->files[1]);
          if (tracks.size() == 0) throw InputError(tracks.source, 0, "no tracks to evaluate");
          Tracks check;
          if (!o->check.empty()) check = three_view_tracks(o->check);
          ReprojectionResult fit, held;
          try {
            const ReprojectionFrame frame = reprojection_frame(tf.T, tracks.xy);
            fit = evaluate_reprojection(frame, tracks.xy);
            if (!o->check.empty()) held = evaluate_reprojection(frame, check.xy);
          } catch (const NumericalError& e) {
            throw NumericalError(tf.source + ": " + e.what());
          }
          std::ostringstream os;
          std::vector<std::string> cols = {"track", "x1", "y1", "x2", "y2", "x3", "y3",
                                           "dx1", "dy1", "dx2", "dy2", "dx3", "dy3", "check"};
          Meta meta;
          meta_set(meta, "trifocal", tf.source);
          meta_set(meta, "residual", "reprojected minus observed, pixels (camera recovery, DLT triangulation)");
          write_header(os, "residuals", 1, tracks.images, meta, cols);
          auto rows = [&](const Tracks& t, const ReprojectionResult& r, double flag) {
            std::vector<double> rec(14);
            for (Eigen::Index q = 0; q < t.xy.rows(); ++q) {
              rec[0] = static_cast<double>(t.id[q]);
              for (int c = 0; c < 6; ++c) rec[1 + c] = t.xy(q, c);
              for (int c = 0; c < 6; ++c) rec[7 + c] = r.residual(q, c);
              rec[13] = flag;
              write_record(os, rec);
            }
          };
          rows(tracks, fit, 0);
          if (!o->check.empty()) rows(check, held, 1);
          write_stats(os, "", fit.stats);
          if (!o->check.empty()) write_stats(os, "check_", held.stats);
          if (!o->plot.empty())
            plot_reprojection(o->plot, tracks.xy, fit.residual, o->check.empty() ? Eigen::MatrixXd(0, 6) : check.xy,
                              o->check.empty() ? Eigen::MatrixXd(0, 6) : held.residual,
                              "reprojection residuals (reprojected minus observed): " + tf.source + " on " + tracks.source,
                              tracks.images);
          write_file_atomic(o->output, os.str());
          tpkit::summary("fit: " + brief(fit.stats));
          if (!o->check.empty()) tpkit::summary("check: " + brief(held.stats));
          return 0;
        };
      },
      tpkit_man_page);
}
