// tp-ortho: orthoimages of images through their RPC models onto a DEM or a height, on one grid; and the shift
// between orthos of one grid (--compare). Options -> library (ortho component) -> GeoTIFF files or a table.
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <thread>
#include <vector>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/ground/reference_dem.hpp"
#include "tpkit/ortho/ortho_alignment.hpp"
#include "tpkit/ortho/ortho_geotiff.hpp"
#include "tpkit/ortho/ortho_grid.hpp"
#include "tpkit/ortho/orthorectify.hpp"
#include "tpkit/rpc/rpc_io.hpp"

extern const char* const tpkit_man_page;

namespace {
using namespace tpkit;

struct Opts {
  std::vector<std::string> inputs, rpc;
  std::string output, dem, dem_datum, crs, like, resampling = "bilinear", occluded = "keep";
  double height = NAN, gsd = 0, wall_slope = 60, min_valid = 0.95;
  std::vector<double> bounds;
  bool compare = false, quiet = false;
  long tile = 128;
  int threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
};

std::string stem_of(const std::string& path) {
  std::string name = path.substr(path.find_last_of('/') + 1);
  const auto dot = name.rfind('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

bool ends_with_tif(const std::string& p) {
  for (const char* e : {".tif", ".tiff", ".TIF", ".TIFF"}) {
    const std::string s(e);
    if (p.size() > s.size() && p.compare(p.size() - s.size(), s.size(), s) == 0) return true;
  }
  return false;
}

// --compare: the table of every pair's shift.
int run_compare(const Opts& o) {
  if (o.inputs.size() < 2) throw UsageError("--compare needs two orthos or more");
  if (!o.rpc.empty() || !o.dem.empty() || !o.dem_datum.empty() || std::isfinite(o.height) || !o.crs.empty() || o.gsd > 0 ||
      !o.bounds.empty() || !o.like.empty() || o.resampling != "bilinear" || o.occluded != "keep" ||
      o.wall_slope != 60)
    throw UsageError("--compare measures orthos already made: --rpc, --dem, --dem-datum, --height, --crs, --gsd, --bounds, --like, --resampling, --occluded and --wall-slope go with orthorectification");
  if (o.tile < 32 || o.tile > 4096) throw UsageError("--tile " + std::to_string(o.tile) + ": 32 to 4096 pixels");
  const std::string out = o.output.empty() ? "-" : o.output;
  check_outputs({{"-o", out}}, o.inputs);
  std::vector<OrthoFileInfo> info;
  for (const auto& f : o.inputs) info.push_back(read_ortho_info(f));
  AlignmentOptions opt;
  opt.tile = o.tile;
  opt.min_valid = o.min_valid;
  opt.threads = o.threads;
  std::vector<ImageRef> refs;
  for (size_t i = 0; i < o.inputs.size(); ++i) refs.push_back({o.inputs[i], info[i].grid.width, info[i].grid.height});
  const OrthoGrid& g = info[0].grid;
  Meta meta{{"grid", "EPSG:" + std::to_string(g.epsg) + ", pixel " + format_number(g.gsd) + " m, corner " + format_number(g.x0) + " " +
                         format_number(g.y0)},
            {"tile", std::to_string(o.tile) + " px, measured where " + format_figure(100 * opt.min_valid) + "% of its pixels are valid in both"},
            {"shift", "of ortho b against ortho a: what a shows at (x, y) b shows at (x + dx, y + dy), grid pixels; east = dx * pixel, north = -dy * pixel, m"}};
  AtomicOutput file(out);
  std::ostream& os = file.stream();
  write_header(os, "ortho-alignment", 1, refs, meta,
               {"a", "b", "tiles", "tried", "dx", "dy", "nmad_dx", "nmad_dy", "shift", "east_m", "north_m", "shift_m"});
  double worst = 0;
  long pairs = 0, unmeasured = 0;
  for (size_t a = 0; a < o.inputs.size(); ++a)
    for (size_t b = a + 1; b < o.inputs.size(); ++b) {
      const PairAlignment p = measure_alignment(o.inputs[a], o.inputs[b], opt);
      const double s = std::hypot(p.dx, p.dy);
      write_record(os, {double(a + 1), double(b + 1), double(p.tiles.size()), double(p.tiles_tried), p.dx, p.dy, p.nmad_dx, p.nmad_dy, s,
                        p.dx * g.gsd, std::isnan(p.dy) ? p.dy : -p.dy * g.gsd, s * g.gsd});  // (nan, not -nan)
      ++pairs;
      if (p.tiles.empty())
        ++unmeasured;
      else
        worst = std::max(worst, s);
    }
  file.commit();
  if (unmeasured) warn(std::to_string(unmeasured) + " of " + std::to_string(pairs) + " pairs have no tile measured (no common valid area, no texture, or holes in every tile: true orthos of a city need --tile 64 or --min-valid 0.5): nan in the table");
  if (!o.quiet)
    summary(std::to_string(pairs) + " pairs of " + std::to_string(o.inputs.size()) + " orthos: largest median shift " + format_figure(worst, 3) +
            " px (" + format_figure(worst * g.gsd, 3) + " m) -> " + out);
  return 0;
}

int run_ortho(const Opts& o) {
  if (o.inputs.empty()) throw UsageError("no IMAGE given");
  if (o.tile != 128) throw UsageError("--tile goes with --compare");
  if (o.min_valid != 0.95) throw UsageError("--min-valid goes with --compare");
  if (o.wall_slope != 60 && o.occluded != "nodata") throw UsageError("--wall-slope goes with --occluded nodata");
  if (o.dem.empty() == !std::isfinite(o.height)) throw UsageError("give the heights: --dem FILE or --height H (one of them)");
  if (!o.dem_datum.empty() && o.dem.empty()) throw UsageError("--dem-datum goes with --dem");
  if (!o.like.empty() && (!o.crs.empty() || o.gsd > 0 || !o.bounds.empty()))
    throw UsageError("--like takes the grid of an ortho: --crs, --gsd and --bounds go without it");
  const Resampling resampling = parse_resampling(o.resampling);
  if (o.occluded != "keep" && o.occluded != "nodata") throw UsageError("--occluded '" + o.occluded + "': keep or nodata");
  if (o.occluded == "nodata" && o.dem.empty()) throw UsageError("--occluded nodata needs a surface that can hide the ground: --dem");
  // outputs: OUTDIR/STEM.ortho.tif, or the file itself for one image and -o NAME.tif
  std::vector<std::string> outs;
  const bool one_file = o.inputs.size() == 1 && ends_with_tif(o.output);
  const std::string dir = o.output.empty() ? "." : o.output;
  if (!one_file && ends_with_tif(o.output)) throw UsageError("-o " + o.output + ": several images need an output folder (-o OUTDIR)");
  for (const auto& im : o.inputs) outs.push_back(one_file ? o.output : dir + "/" + stem_of(im) + ".ortho.tif");
  for (size_t i = 0; i < outs.size(); ++i)
    for (size_t k = 0; k < i; ++k)
      if (outs[i] == outs[k]) throw UsageError(o.inputs[k] + " and " + o.inputs[i] + " would both be written to " + outs[i] + ": give them different names");
  std::vector<std::string> inputs = o.inputs;
  if (!o.dem.empty()) inputs.push_back(o.dem);
  if (!o.like.empty()) inputs.push_back(o.like);
  if (!one_file) create_output_dir(dir);
  std::vector<std::pair<std::string, std::string>> claims;
  for (const auto& f : outs) claims.push_back({"-o", f});
  check_outputs(claims, inputs);

  // the models and the heights
  const auto overrides = resolve_rpc_overrides(parse_rpc_overrides(o.rpc), o.inputs);
  std::vector<RpcSource> src;
  std::vector<OrthoSource> sources;
  for (const auto& im : o.inputs) {
    src.push_back(load_image_rpc(im, overrides));
    const ImageInfo info = image_info(im);
    sources.push_back({src.back().model, info.width, info.height});
  }
  std::unique_ptr<ReferenceDem> dem;
  if (!o.dem.empty()) dem = std::make_unique<ReferenceDem>(o.dem, ReferenceDemOptions{o.dem_datum});
  HeightAt height_at = [&](double lon, double lat) {
    double h = o.height;
    if (dem && !dem->height(lon, lat, h)) return double(NAN);
    return h;
  };
  OrthoSurface surface;
  surface.dem = dem.get();
  surface.height = o.height;
  if (!dem)
    for (size_t i = 0; i < sources.size(); ++i) {
      const RpcModel& m = sources[i].model;
      if (o.height < m.height_min() - m.height_scale || o.height > m.height_max() + m.height_scale)
        warn("--height " + format_number(o.height) + " m is far outside " + o.inputs[i] + "'s model height range (" + format_number(m.height_min()) +
             " to " + format_number(m.height_max()) + " m above the ellipsoid): heights are above the ellipsoid, not the geoid");
    }

  // the grid
  OrthoGrid grid;
  if (!o.like.empty()) {
    grid = read_ortho_info(o.like).grid;
  } else {
    const int epsg = resolve_ortho_crs(o.crs.empty() ? "utm" : o.crs, sources[0].model.lon_off, sources[0].model.lat_off);
    double gsd = o.gsd;
    if (gsd == 0) {
      gsd = INFINITY;
      for (const auto& s : sources) gsd = std::min(gsd, ground_sampling(s, height_at));
      gsd = std::max(0.01, std::round(gsd * 100) / 100);  // to the centimetre: a round figure others can reuse
    }
    if (o.bounds.empty()) {
      GridCrs crs(epsg);
      std::vector<Eigen::Vector2d> pts;
      for (const auto& s : sources) {
        std::vector<Eigen::Vector2d> f = image_footprint(s, height_at);
        std::vector<double> x, y;
        for (const auto& p : f) {
          x.push_back(p[0]);
          y.push_back(p[1]);
        }
        crs.from_lonlat(x.size(), x.data(), y.data());
        for (size_t i = 0; i < x.size(); ++i) pts.emplace_back(x[i], y[i]);
      }
      grid = grid_covering(epsg, gsd, pts);
    } else {
      grid = grid_of_bounds(epsg, gsd, o.bounds[0], o.bounds[1], o.bounds[2], o.bounds[3]);
    }
  }
  check_grid(grid, o.like.empty() ? "the grid" : o.like);
  const GridCrs crs(grid.epsg, o.like.empty() ? "--crs" : o.like);
  if (o.occluded == "nodata") surface.top = highest_height(surface, grid, crs);  // one search bound for every image

  // one ortho per image
  std::vector<std::string> lines;
  for (size_t i = 0; i < o.inputs.size(); ++i) {
    OrthoOptions opt;
    opt.resampling = resampling;
    opt.threads = o.threads;
    opt.hide_occluded = o.occluded == "nodata";
    opt.wall_slope_deg = o.wall_slope;
    opt.description = "tpkit ortho of " + o.inputs[i] + " through " + src[i].path + " (" + rpc_form_name(src[i].form) + "), heights " +
                      (dem ? "of " + o.dem + " (" + dem->datum() + ")" : format_number(o.height) + " m above the ellipsoid") + ", " + o.resampling +
                      (opt.hide_occluded ? ", hidden ground nodata" : "");
    const auto t0 = std::chrono::steady_clock::now();
    const OrthoStats st = orthorectify(o.inputs[i], sources[i].model, grid, crs, surface, opt, outs[i]);
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (st.valid == 0)
      throw InputError(o.inputs[i], 0, "no pixel of the grid sees this image" + std::string(st.no_height ? " where the DEM has heights" : "") +
                                           " (--bounds, --like, or the DEM's extent?)");
    if (st.no_height > 0)
      warn(o.inputs[i] + ": " + std::to_string(st.no_height) + " grid pixels have no height (off the DEM, or its nodata): nodata in the ortho");
    lines.push_back(o.inputs[i] + " -> " + outs[i] + ": " + format_figure(100.0 * st.valid / st.pixels, 3) + "% of the grid valid, " +
                    (opt.hide_occluded ? format_figure(100.0 * st.hidden / st.pixels, 3) + "% hidden from the view (nodata), " : "") +
                    std::to_string(st.bands) + " band(s) " + st.type + ", " + format_figure(sec, 3) + " s (" +
                    format_figure(st.pixels / sec / 1e6, 3) + " Mpx/s)");
  }
  if (!o.quiet) {
    summary("grid " + crs.name() + ", " + std::to_string(grid.width) + " x " + std::to_string(grid.height) + " px of " + format_number(grid.gsd) +
            " m, corner " + format_number(grid.x0) + " " + format_number(grid.y0));
    for (const auto& l : lines) summary(l);
  }
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace tpkit;
  return run_tool("tp-ortho", argc, argv, [&](CLI::App& app) -> std::function<int()> {
    auto o = std::make_shared<Opts>();
    app.add_option("IMAGE", o->inputs, "images to orthorectify (with --compare: orthos of one grid)")->required();
    app.add_option("--rpc", o->rpc, "IMAGE=FILE: the model of IMAGE from FILE (_rpc.txt, .RPB, DIMAP .XML, .geom, .aux.xml), e.g. rpc-adjust's output");
    app.add_option("--dem", o->dem, "heights from this GeoTIFF DEM (any CRS; heights above --dem-datum)");
    app.add_option("--dem-datum", o->dem_datum, "the DEM's heights: ellipsoid | egm96 | egm2008 | a PROJ vertical grid file (default: the DEM's vertical GeoTIFF keys, ellipsoid without them)");
    app.add_option("--height", o->height, "one height everywhere, metres above the WGS 84 ellipsoid");
    app.add_option("--crs", o->crs, "the grid's CRS: utm (the first image's zone, default) | EPSG:N | a PROJ string with an EPSG code");
    app.add_option("--gsd", o->gsd, "pixel size of the grid, metres (default: the finest ground sampling of the images, to the cm)")->check(Positive);
    app.add_option("--bounds", o->bounds, "XMIN YMIN XMAX YMAX of the grid in its CRS, metres (default: the union of the footprints)")->expected(4);
    app.add_option("--like", o->like, "the grid of this ortho (CRS, corner, pixel size, size)");
    app.add_option("--resampling", o->resampling, "bilinear (default) | bicubic");
    app.add_option("--occluded", o->occluded, "ground the view cannot see behind what the DEM holds (buildings, trees, ridges): keep (default: the surface that hides it, as gdalwarp) | nodata (a true ortho)");
    app.add_option("--threads", o->threads, "worker threads (default: the machine's cores)")->check(CLI::Range(1, kMaxThreads));
    app.add_option("-o,--output", o->output, "output folder (IMAGE's stem + .ortho.tif; default .), or a .tif for one image; --compare: the table (default -)");
    app.add_flag("--compare", o->compare, "measure the shift between every pair of orthos (IMAGE...) of one grid");
    app.add_option("--tile", o->tile, "--compare: tile side, pixels (default 128)");
    app.add_option("--min-valid", o->min_valid, "--compare: share of a tile's pixels valid in both orthos for it to be measured (default 0.95)")->check(CLI::Range(0.05, 1.0));
    app.add_option("--wall-slope", o->wall_slope, "with --occluded nodata: DEM slopes steeper than this, degrees, are walls and nodata too (default 60; 90: none)")->check(CLI::Range(1.0, 90.0));
    app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
    return [o]() { return o->compare ? run_compare(*o) : run_ortho(*o); };
  }, tpkit_man_page);
}
