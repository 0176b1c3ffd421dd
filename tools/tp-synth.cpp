// tp-synth: a synthetic satellite triplet, or a block of views, with exact ground truth (man/tp-synth.1).
#include <iostream>
#include <memory>
#include <sstream>

#include "tpkit/core/error.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/synth/synth_scene.hpp"
#include "tpkit/synth/synth_structures.hpp"
#include "tpkit/core/tool_support.hpp"

extern const char* const tpkit_man_page;

int main(int argc, char** argv) {
  struct Opts {
    std::string out;
    tpkit::SynthParams p;
    int threads = 0;
    std::string cross_track;
    std::string origin;
    std::vector<std::string> rpc_bias;
    double random_bias = 0;
    std::string scene = "default";
    double buildings = 0, trees = 0;  // where given (else the --scene preset's)
  };
  return tpkit::run_tool(
      "tp-synth", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("-o,--out", o->out, "output directory (created if needed)")->required();
        app.add_option("--seed", o->p.seed, "random seed");
        app.add_option("--size", o->p.size, "width = height of each view (pixels)");
        app.add_option("--relief", o->p.relief, "terrain relief, max - min height over the scene (m)");
        app.add_option("--gsd", o->p.gsd, "ground sampling distance of the nadir view (m/pixel)");
        app.add_option("--camera", o->p.camera, "affine or perspective");
        app.add_option("--points", o->p.points, "number of truth tracks");
        app.add_option("--noise", o->p.noise, "sensor noise sigma (DN, 12-bit range)");
        app.add_option("--supersample", o->p.supersample, "n x n samples per pixel");
        app.add_option("--threads", o->threads, "rendering threads (0: all cores)");
        app.add_option("--cross-track", o->cross_track, "cross-track angle(s) of the views, DEG or DEG,DEG,DEG");
        app.add_option("--origin", o->origin, "LAT,LON,H of the scene centre (degrees, degrees, m above the WGS84 ellipsoid)");
        app.add_option("--rpc-bias", o->rpc_bias, "VIEW:dx,dy[,dxy,dyy[,dxx,dyx]]: bias injected into a view's RPC (px, px/px)");
        app.add_option("--views", o->p.views, "views in all (3: the tri-stereo; 2 to 96)");
        app.add_option("--dates", o->p.dates, "acquisitions of a block (default: views / 3)")
            ->check(tpkit::Positive);  // 0 is the default's mark in SynthParams, not a count to give
        app.add_option("--second-date", o->p.date2, "views 2..N from a second date: strength 0..1 of tone, season, texture, sun changes");
        app.add_option("--clouds", o->p.clouds, "views 2..N: fraction of the ground under clouds, with their shadows");
        app.add_option("--water", o->p.water, "fraction of the ground under featureless water (every view)");
        app.add_option("--nodata-band", o->p.nodata, "views 2..N: fraction of the columns, from the left, written as 0 (nodata)");
        app.add_option("--blur", o->p.blur, "views 2..N: Gaussian PSF of this sigma (pixels, 0 to 5) before the noise");
        app.add_option("--resolution-ratio", o->p.resolution_ratio, "views 2..N: R times the ground sampling distance (1 to 4)");
        app.add_option("--rotation", o->p.rotation, "views 2..N: image axes turned about the optical axis (degrees)");
        app.add_option("--scene", o->scene, "default, or buildings: a town of buildings and trees (--buildings 0.45 --trees 0.35)");
        CLI::Option* ob = app.add_option("--buildings", o->buildings, "fraction of the 30 m lots that hold a building (0 to 1; vertical walls, flat roofs)");
        CLI::Option* ot = app.add_option("--trees", o->trees, "fraction of the other lots that hold trees (0 to 1)");
        app.add_option("--random-bias", o->random_bias,
                       "seeded RPC bias of at most PX pixels (shift, drift, affine) on every view but view 1 and those of --rpc-bias");
        return [o, ob, ot]() {
          if (!o->cross_track.empty()) o->p.cross_track = tpkit::parse_cross_track(o->cross_track);
          tpkit::apply_scene_preset(o->scene, o->p);
          if (ob->count()) o->p.buildings = o->buildings;
          if (ot->count()) o->p.trees = o->trees;
          tpkit::check_params(o->p);
          if (o->threads < 0 || o->threads > tpkit::kMaxThreads)
            throw tpkit::UsageError("--threads must be between 0 and " + std::to_string(tpkit::kMaxThreads));
          const tpkit::SynthScene scene(o->p);
          tpkit::SynthWriteOptions w;
          w.threads = o->threads;
          if (!o->origin.empty()) w.origin = tpkit::parse_geo_origin(o->origin, "--origin");
          for (const auto& b : o->rpc_bias) {
            auto vb = tpkit::parse_view_bias(b, o->p.views);
            if (!w.rpc_bias.emplace(vb.first, vb.second).second)
              throw tpkit::UsageError("--rpc-bias: view " + std::to_string(vb.first + 1) + " given twice");
          }
          if (!(o->random_bias >= 0 && o->random_bias <= 1000))
            throw tpkit::UsageError("--random-bias must be between 0 and 1000 pixels");
          if (o->random_bias > 0)
            for (int v = 1; v < scene.views(); ++v)  // view 1 stays unbiased; --rpc-bias views keep theirs
              w.rpc_bias.emplace(v, tpkit::synth_random_bias(scene, v, o->random_bias));
          tpkit::write_synth_scene(scene, o->out, w);
          std::ostringstream line;
          line << "wrote " << o->out << ": " << scene.views() << " views " << o->p.size << "x" << o->p.size << " (" << o->p.camera
               << "), scene square " << scene.scene_size() << " m, relief " << o->p.relief << " m, " << o->p.points
               << " truth tracks";
          if (scene.has_structures())
            line << ", " << scene.structures().buildings() << " buildings, " << scene.structures().trees() << " trees";
          tpkit::summary(line.str());
          return 0;
        };
      },
      tpkit_man_page);
}
