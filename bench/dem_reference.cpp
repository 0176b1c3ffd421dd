// bench_dem_reference: a reference DEM degraded as real ones are, from tp-synth's truth terrain (issue 25):
// resampled (bilinear) at POSTING m on a UTM grid (the zone of the DEM's centre) covering the truth DEM,
// Gaussian noise of SIGMA m added, heights above DATUM (egm96: H = h - N), written as a tiled float32
// GeoTIFF by write_reference_dem. Cells the truth DEM does not cover are nodata. With SHIFT_E SHIFT_N SHIFT_U
// (m, UTM grid axes) the DEM is the terrain moved by that translation: a reference the truth ground points
// must be moved by the same shift to fit (tests of tp-ground --align).
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <random>
#include <string>

#include <proj.h>

#include "tpkit/core/image_io.hpp"
#include "tpkit/ground/reference_dem.hpp"

using namespace tpkit;

int main(int argc, char** argv) {
  const std::string usage =
      "usage: bench_dem_reference TRUTH.dem.tif OUT.tif [POSTING_M (30)] [SIGMA_M (2)] [DATUM (egm96)] [SEED (1)] [SHIFT_E SHIFT_N SHIFT_U (0 0 0)]";
  if (argc < 3 || std::string(argv[1]) == "--help") {
    std::cout << usage << "\n";
    return argc < 3 && !(argc == 2 && std::string(argv[1]) == "--help") ? 2 : 0;
  }
  try {
    const std::string truth_path = argv[1], out = argv[2];
    const double posting = argc > 3 ? std::atof(argv[3]) : 30, sigma = argc > 4 ? std::atof(argv[4]) : 2;
    const std::string datum = argc > 5 ? argv[5] : "egm96";
    const unsigned seed = argc > 6 ? static_cast<unsigned>(std::atoi(argv[6])) : 1;
    const double se = argc > 9 ? std::atof(argv[7]) : 0, sn = argc > 9 ? std::atof(argv[8]) : 0, su = argc > 9 ? std::atof(argv[9]) : 0;
    const GeoGrid g = read_geotiff_grid(truth_path);  // for its extent
    const ReferenceDem truth(truth_path);
    const VerticalDatum vd(datum);
    const double lon_c = g.lon0 + g.dlon * (g.width - 1) / 2, lat_c = g.lat0 - g.dlat * (g.height - 1) / 2;
    const int zone = static_cast<int>(std::floor((lon_c + 180) / 6)) + 1;
    const int epsg = (lat_c >= 0 ? 32600 : 32700) + zone;
    PJ_CONTEXT* ctx = proj_context_create();
    PJ* raw = proj_create_crs_to_crs(ctx, "EPSG:4326", ("EPSG:" + std::to_string(epsg)).c_str(), nullptr);
    PJ* pj = proj_normalize_for_visualization(ctx, raw);
    // UTM box of the truth DEM's corners, snapped to the posting.
    double e_lo = INFINITY, e_hi = -INFINITY, n_lo = INFINITY, n_hi = -INFINITY;
    for (int c = 0; c < 4; ++c) {
      const double lon = g.lon0 + (c & 1 ? g.dlon * (g.width - 1) : 0), lat = g.lat0 - (c & 2 ? g.dlat * (g.height - 1) : 0);
      const PJ_COORD p = proj_trans(pj, PJ_FWD, proj_coord(lon, lat, 0, 0));
      e_lo = std::min(e_lo, p.xy.x);
      e_hi = std::max(e_hi, p.xy.x);
      n_lo = std::min(n_lo, p.xy.y);
      n_hi = std::max(n_hi, p.xy.y);
    }
    DemRaster r;
    r.epsg = epsg;
    r.dx = r.dy = posting;
    r.x0 = std::floor(e_lo / posting) * posting;
    r.y0 = std::ceil(n_hi / posting) * posting;
    r.width = static_cast<long>(std::ceil((e_hi - r.x0) / posting)) + 1;
    r.height = static_cast<long>(std::ceil((r.y0 - n_lo) / posting)) + 1;
    r.datum = datum;
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0, sigma);
    long known = 0;
    for (long y = 0; y < r.height; ++y)
      for (long x = 0; x < r.width; ++x) {
        const PJ_COORD q = proj_trans(pj, PJ_INV, proj_coord(r.x0 + x * posting - se, r.y0 - y * posting - sn, 0, 0));
        double h;
        float v = NAN;
        if (truth.height(q.lp.lam, q.lp.phi, h)) {
          v = static_cast<float>(h + su - vd.undulation(q.lp.lam, q.lp.phi) + noise(rng));
          ++known;
        }
        r.data.push_back(v);
      }
    proj_destroy(pj);
    proj_destroy(raw);
    proj_context_destroy(ctx);
    write_reference_dem(out, r);
    std::cout << "bench_dem_reference: " << out << ": EPSG:" << epsg << ", " << r.width << "x" << r.height << " cells of "
              << posting << " m (" << known << " known), noise sigma " << sigma << " m, heights above " << datum << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "bench_dem_reference: " << e.what() << "\n";
    return 1;
  }
}
