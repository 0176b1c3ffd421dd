// RPC models against tp-synth's truth: how far the models put the truth ground points from the truth
// pixels, view by view over the truth points each view sees (a block's truth tracks are nan where a view
// does not see the point), and (optionally) how far a ground file's heights are from the truth terrain
// (truth.dem.tif).
// The figure of rpc-adjust on tp-match's own tracks of a biased synthetic triplet:
//   tp-synth -o syn --rpc-bias 2:6,-8,0.002,-0.001,0.001,0.0015 --rpc-bias 3:-10,4,0.001,0.0005,-0.0008,0.0004
//   tp-match ... ; tp-chain ... -o triplet.tracks ; rpc-adjust ... --fixed syn/view1.tif --dem syn/truth.dem.tif -o adj
//   build*/bin/bench_rpc_truth syn/truth.tracks syn/view1_rpc.txt adj/view2_rpc.txt adj/view3_rpc.txt
//       [--ground adj/ground.points syn/truth.dem.tif]
// One model per image of the tracks file (a block of 12 views: 12 models), in its order.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>
#include <algorithm>

#include "tpkit/core/formats.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/core/text_table.hpp"

int main(int argc, char** argv) {
  const char* usage = "usage: bench_rpc_truth TRUTH.tracks MODEL... [--ground GROUND DEM]\n";
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::fputs(usage, stdout);
    return 0;
  }
  std::vector<std::string> models;
  std::string ground, dem_path;
  for (int i = 2; i < argc; ++i) {
    if (std::string(argv[i]) == "--ground" && i + 2 < argc) {
      ground = argv[++i];
      dem_path = argv[++i];
    } else {
      models.push_back(argv[i]);
    }
  }
  if (argc < 3 || models.empty()) {
    std::fputs(usage, stderr);
    return 2;
  }
  const tpkit::Tracks t = tpkit::read_tracks(argv[1]);
  const int lon = t.extra.find("lon");
  if (lon < 0) {
    std::fprintf(stderr, "%s: not tp-synth truth tracks with lon lat h columns\n", argv[1]);
    return 1;
  }
  if (static_cast<int>(models.size()) != t.views()) {
    std::fprintf(stderr, "bench_rpc_truth: %zu models for the %d images of %s\n", models.size(), t.views(), argv[1]);
    return 2;
  }
  double all = 0, worst = 0;
  long nall = 0;
  for (int v = 0; v < t.views(); ++v) {
    const tpkit::RpcModel m = tpkit::read_rpc_file(models[static_cast<size_t>(v)]);
    double s = 0;
    long n = 0;
    for (size_t i = 0; i < t.size(); ++i) {
      if (!t.seen(i, v)) continue;
      s += (m.project(t.extra.values(i, lon), t.extra.values(i, lon + 1), t.extra.values(i, lon + 2)) - t.point(i, v))
               .squaredNorm();
      ++n;
    }
    all += s;
    nall += n;
    const double rms = n ? std::sqrt(s / n) : NAN;
    worst = std::max(worst, rms);
    std::printf("view %d (%s): %ld truth points, truth reprojection rms %.5f px\n", v + 1, models[static_cast<size_t>(v)].c_str(), n, rms);
  }
  std::printf("all views: truth reprojection rms %.5f px over %ld observations of %zu truth points; worst view %.5f px\n",
              std::sqrt(all / static_cast<double>(nall)), nall, t.size(), worst);
  if (!ground.empty()) {
    const auto dem = tpkit::dem_height_prior(tpkit::read_geotiff_grid(dem_path), 1);
    tpkit::ReadOptions ro;
    ro.kind = "ground";
    const auto g = tpkit::read_table_file(ground, ro);
    // the points a tool flags (its residual above --flag: blunders) apart: their heights are not the terrain's
    const int lo = g.require("lon"), la = g.require("lat"), h = g.require("h"), fl = g.find("flagged");
    double s = 0;
    long n = 0, flagged = 0;
    for (const auto& r : g.rows) {
      double z;
      if (!dem.at(r[lo], r[la], z, nullptr)) continue;
      if (fl >= 0 && r[fl] != 0) {
        ++flagged;
        continue;
      }
      s += (r[h] - z) * (r[h] - z);
      ++n;
    }
    std::printf("%s: %ld points on the DEM, height rms %.4f m (%ld flagged points left out)\n", ground.c_str(), n,
                n ? std::sqrt(s / n) : NAN, flagged);
  }
  return 0;
}
