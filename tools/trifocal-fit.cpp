// trifocal-fit: the trifocal tensor of three views from a tracks file (man/trifocal-fit.1).
#include <iostream>
#include <memory>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/geometry/reproj_eval.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/geometry/trifocal_three_f.hpp"
#include "tpkit/geometry/trifocal_fit.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::string method = "ml";
  double ransac = 0;
  std::uint64_t seed = 1;
  std::string cameras, inliers, input = "-", output = "-";
};

std::string num(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "trifocal-fit", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("-m,--method", o->method, "dlt, affine-dlt, algebraic, minimal, three-f, ml");
        CLI::Option* ransac = app.add_option("--ransac", o->ransac, "robust fit; inlier threshold in pixels");
        app.add_option("--seed", o->seed, "seed of the robust sampling");
        app.add_option("--cameras", o->cameras, "also write the cameras recovered from the tensor");
        app.add_option("--inliers", o->inliers, "with --ransac: write the tracks with an inlier column");
        app.add_option("tracks", o->input, "tracks file with three views, - for stdin");
        app.add_option("-o,--output", o->output, "trifocal file, - for stdout");
        return [o, ransac]() {
          using namespace tpkit;
          if (ransac->count() > 0 && !(o->ransac > 0))
            throw UsageError("--ransac: the inlier threshold must be a positive number of pixels, got " + num(o->ransac));
          check_outputs({{"-o", o->output}, {"--cameras", o->cameras}, {"--inliers", o->inliers}}, {o->input});
          const TrifocalMethod m = parse_trifocal_method(o->method);
          if (!o->inliers.empty() && !(o->ransac > 0)) throw UsageError("--inliers needs --ransac");
          if (o->ransac < 0) throw UsageError("--ransac: the threshold must be positive");
          size_t left_out = 0;
          const Tracks tracks = read_tracks_seen_in_all_views(o->input, 3, &left_out);
          if (left_out)
            warn(tracks.source + ": " + std::to_string(left_out) + " tracks not seen in all three views left out; fitting the " +
                 std::to_string(tracks.size()) + " that are");
          Trifocal out;
          out.images = tracks.images;
          Eigen::MatrixXd fit_xy;
          std::vector<char> mask;
          try {
            if (o->ransac > 0) {
              RansacOptions ro;
              ro.threshold = o->ransac;
              ro.seed = o->seed;
              RobustTrifocalFit r = fit_trifocal_ransac(m, tracks.xy, ro);
              out.T = r.T;
              mask = r.inlier;
              fit_xy.resize(static_cast<Eigen::Index>(r.inliers), 6);
              Eigen::Index k = 0;
              for (Eigen::Index q = 0; q < tracks.xy.rows(); ++q)
                if (mask[q]) fit_xy.row(k++) = tracks.xy.row(q);
              meta_set(out.meta, "ransac_threshold_px", num(o->ransac));
              meta_set(out.meta, "seed", std::to_string(o->seed));
              meta_set(out.meta, "inliers", std::to_string(r.inliers));
              meta_set(out.meta, "ransac_iterations", std::to_string(r.iterations));
            } else {
              out.T = fit_trifocal(m, tracks.xy);
              fit_xy = tracks.xy;
            }
          } catch (const InputError& e) {
            throw InputError(tracks.source, 0, e.what());
          }
          const ReprojectionFrame frame = reprojection_frame(out.T, fit_xy);
          const ReprojectionStats st = evaluate_reprojection(frame, fit_xy).stats;
          meta_set(out.meta, "method", trifocal_method_name(m));
          if (m == TrifocalMethod::ThreeF) {
            // near-coplanar viewing directions: three-f is marked (see trifocal_three_f.hpp)
            const double angle = three_f_epipolar_angle(three_fundamental_linear(fit_xy), fit_xy);
            meta_set(out.meta, "epipolar_angle_deg", num(std::round(angle * 1e4) / 1e4));
            if (angle < kThreeFWarnAngleDeg)
              warn("three-f: the epipolar lines of two views meet in the third at " + num(std::round(angle * 1e3) / 1e3) +
                   " deg (viewing directions nearly in one plane): the three fundamental matrices determine the third "
                   "camera poorly and the transfer error is inflated; -m ml is the better fit here");
          }
          meta_set(out.meta, "tracks", std::to_string(tracks.size()));
          meta_set(out.meta, "fit_tracks", std::to_string(fit_xy.rows()));
          meta_set(out.meta, "rmse_px", num(st.rmse));
          meta_set(out.meta, "source", tracks.source);
          // everything is computed before anything is written
          Cameras cams;
          if (!o->cameras.empty()) {
            cams.images = tracks.images;
            meta_set(cams.meta, "method", trifocal_method_name(m));
            meta_set(cams.meta, "frame", "projective, recovered from the tensor (P1 = [I|0], unit third rows before denormalization)");
            cams.P.assign(frame.P_pixels.begin(), frame.P_pixels.end());
          }
          Tracks flagged;
          if (!o->inliers.empty()) {
            flagged = tracks;
            flagged.extra.names.push_back("inlier");
            Eigen::MatrixXd ev(tracks.xy.rows(), flagged.extra.names.size());
            if (tracks.extra.values.cols() > 0) ev.leftCols(tracks.extra.values.cols()) = tracks.extra.values;
            for (Eigen::Index q = 0; q < tracks.xy.rows(); ++q) ev(q, ev.cols() - 1) = mask[q] ? 1 : 0;
            flagged.extra.values = ev;
          }
          save_trifocal(o->output, out);
          if (!o->cameras.empty()) save_cameras(o->cameras, cams);
          if (!o->inliers.empty()) save_tracks(o->inliers, flagged);
          tpkit::summary(trifocal_method_name(m) + ": " + std::to_string(fit_xy.rows()) + " of " + std::to_string(tracks.size()) +
                         " tracks fitted, reprojection rmse " + num(st.rmse) + " px");
          return 0;
        };
      },
      tpkit_man_page);
}
