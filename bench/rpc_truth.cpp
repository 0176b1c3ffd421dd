// RPC models against tp-synth's truth: how far the models put the truth ground points from the truth
// pixels, and (optionally) how far a ground file's heights are from the truth terrain (truth.dem.tif).
// The figure of rpc-adjust on tp-match's own tracks of a biased synthetic triplet:
//   tp-synth -o syn --rpc-bias 2:6,-8,0.002,-0.001,0.001,0.0015 --rpc-bias 3:-10,4,0.001,0.0005,-0.0008,0.0004
//   tp-match ... ; tp-chain ... -o triplet.tracks ; rpc-adjust ... --fixed syn/view1.tif --dem syn/truth.dem.tif -o adj
//   build*/bin/bench_rpc_truth syn/truth.tracks syn/view1_rpc.txt adj/view2_rpc.txt adj/view3_rpc.txt
//       [adj/ground.points syn/truth.dem.tif]
#include <cmath>
#include <cstdio>
#include <string>

#include "tpkit/core/formats.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/core/text_table.hpp"

int main(int argc, char** argv) {
  const char* usage = "usage: bench_rpc_truth TRUTH.tracks MODEL1 MODEL2 MODEL3 [GROUND DEM]\n";
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::fputs(usage, stdout);
    return 0;
  }
  if (argc != 5 && argc != 7) {
    std::fputs(usage, stderr);
    return 2;
  }
  const tpkit::Tracks t = tpkit::read_tracks(argv[1]);
  const int lon = t.extra.find("lon");
  if (lon < 0 || t.views() != 3) {
    std::fprintf(stderr, "%s: not tp-synth truth tracks with lon lat h columns\n", argv[1]);
    return 1;
  }
  double all = 0;
  for (int v = 0; v < 3; ++v) {
    const tpkit::RpcModel m = tpkit::read_rpc_file(argv[2 + v]);
    double s = 0;
    for (size_t i = 0; i < t.size(); ++i)
      s += (m.project(t.extra.values(i, lon), t.extra.values(i, lon + 1), t.extra.values(i, lon + 2)) - t.point(i, v))
               .squaredNorm();
    all += s;
    std::printf("view %d (%s): truth reprojection rms %.5f px\n", v + 1, argv[2 + v], std::sqrt(s / t.size()));
  }
  std::printf("all views: truth reprojection rms %.5f px over %zu truth points\n", std::sqrt(all / (3.0 * t.size())), t.size());
  if (argc == 7) {
    const auto dem = tpkit::dem_height_prior(tpkit::read_geotiff_grid(argv[6]), 1);
    tpkit::ReadOptions ro;
    ro.kind = "ground";
    const auto g = tpkit::read_table_file(argv[5], ro);
    const int lo = g.require("lon"), la = g.require("lat"), h = g.require("h");
    double s = 0;
    long n = 0;
    for (const auto& r : g.rows) {
      double z;
      if (dem.at(r[lo], r[la], z, nullptr)) {
        s += (r[h] - z) * (r[h] - z);
        ++n;
      }
    }
    std::printf("%s: %ld points on the DEM, height rms %.4f m\n", argv[5], n, n ? std::sqrt(s / n) : NAN);
  }
  return 0;
}
