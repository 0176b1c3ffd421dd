// Rendering and writing of the tp-synth triplet (synth_scene.hpp: SynthScene::render_rows,
// write_synth_scene).
//
// Each pixel is the mean radiance over n x n samples at offsets (k + 0.5) / n - 0.5 from its centre (box
// pixel response), each sample the first terrain intersection of its viewing ray. Exact casts (grid
// traversal + bracketing, synth_terrain.hpp) are made at the pixel corners; a sample inside a pixel whose
// four corner hits are consistent (no occlusion edge) is found by Newton from the bilinear interpolation
// of the corner ray parameters, every other sample by an exact cast.
#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/rpc/rpc_bias.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/synth/synth_conditions.hpp"
#include "tpkit/synth/synth_noise.hpp"
#include "tpkit/synth/synth_scene.hpp"
#include "tpkit/synth/synth_terrain.hpp"
#include "tpkit/core/tool_support.hpp"

namespace tpkit {

namespace {
// Standard normal deviate from a hash (Box-Muller on two 53-bit uniforms).
double gauss(uint64_t h) {
  const double u1 = (static_cast<double>(synth::mix64(h) >> 11) + 1) * (1.0 / 9007199254740993.0);
  const double u2 = synth::unit(synth::mix64(h ^ 0xabcdef12345ULL));
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * 3.14159265358979323846 * u2);
}
}  // namespace

void SynthScene::render_rows(int view, long y0, long rows, uint16_t* out) const {
  const long W = params().size;
  const int ns = static_cast<int>(params().supersample);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Exact ray parameters at the pixel corners (x - 0.5, y - 0.5), (rows + 1) x (W + 1).
  std::vector<double> tc(static_cast<size_t>(rows + 1) * (W + 1));
  Eigen::Vector3d o, d;
  auto cast = [&](double x, double y) {
    ray(view, x, y, o, d);
    // 1 mm is plenty for a starting guess and for the smoothness test below.
    const auto t = terrain_().intersect(o, d, 1e-3);
    return t ? *t : nan;
  };
  for (long j = 0; j <= rows; ++j)
    for (long i = 0; i <= W; ++i) tc[static_cast<size_t>(j) * (W + 1) + i] = cast(i - 0.5, y0 + j - 0.5);
  // Corner parameters of a smooth pixel differ by a few pixel sizes at most; a larger jump means an
  // occlusion edge (or a grazing ray) inside the pixel.
  const double jump = 6 * params().gsd;
  const uint64_t ns_seed = synth::hash(params().seed, 0x401e, view);
  const double g = gain(view), off = offset(view), sigma = params().noise;
  const bool conditions = synth_has_conditions(params());  // else exactly the scene as before
  for (long j = 0; j < rows; ++j) {
    const long y = y0 + j;
    for (long x = 0; x < W; ++x) {
      const double* r0 = &tc[static_cast<size_t>(j) * (W + 1) + x];
      const double* r1 = r0 + (W + 1);
      const double t00 = r0[0], t10 = r0[1], t01 = r1[0], t11 = r1[1];
      const bool smooth = std::isfinite(t00) && std::isfinite(t10) && std::isfinite(t01) && std::isfinite(t11) &&
                          std::abs(t10 - t00) < jump && std::abs(t11 - t01) < jump && std::abs(t01 - t00) < jump &&
                          std::abs(t11 - t10) < jump;
      double sum = 0;
      for (int b = 0; b < ns; ++b) {
        const double fy = (b + 0.5) / ns;
        for (int a = 0; a < ns; ++a) {
          const double fx = (a + 0.5) / ns;
          const double sx = x - 0.5 + fx, sy = y - 0.5 + fy;
          ray(view, sx, sy, o, d);
          std::optional<double> t;
          Eigen::Vector2d grad;
          // Newton until a step is below 1 cm: the position error is then ~ (curvature / slope) x step^2, below
          // 1e-4 m for the terrains made here; the gradient of its last evaluation shades.
          if (smooth) t = terrain_().refine(o, d, (1 - fy) * ((1 - fx) * t00 + fx * t10) + fy * ((1 - fx) * t01 + fx * t11), 1e-2, &grad);
          if (!t) {
            t = terrain_().intersect(o, d);
            if (!t) continue;  // cannot happen inside the terrain grid: counts as black
            const Eigen::Vector3d X = o + *t * d;
            terrain_().height(X.x(), X.y(), &grad);
          }
          const Eigen::Vector3d X = o + *t * d;
          sum += conditions ? synth_condition_radiance(*this, view, X.x(), X.y(), grad) : radiance(X.x(), X.y(), grad);
        }
      }
      double dn = g * sum / (ns * ns) + off;
      if (sigma > 0) dn += sigma * gauss(synth::hash(ns_seed, y, x));
      if (conditions) dn = synth_condition_dn(params(), view, x, dn);
      dn = std::clamp(std::round(dn), 0.0, 4095.0);
      out[static_cast<size_t>(j) * W + x] = static_cast<uint16_t>(dn);
    }
  }
}

namespace {
// The views' RPC00B models (biased where asked), each checked against its camera; the fit errors and the
// origin go into the metadata.
std::vector<RpcModel> synth_rpc_models(const SynthScene& scene, const SynthGeoFrame& geo,
                                       const std::map<int, ImageBias>& bias, Meta& meta) {
  std::vector<RpcModel> out;
  const auto& o = geo.origin();
  meta_set(meta, "origin", format_number(o.lat) + "," + format_number(o.lon) + "," + format_number(o.h) +
                               " (lat, lon degrees WGS84, h m above the ellipsoid of the scene centre X = Y = S/2, Z = 0)");
  for (int v = 0; v < scene.views(); ++v) {
    auto it = bias.find(v);
    RpcFit f = synth_view_rpc(scene, geo, v, it == bias.end() ? ImageBias{} : it->second);
    if (!(f.max_px <= 0.01))
      throw NumericalError("the RPC fitted to view " + std::to_string(v + 1) + " misses its camera by " +
                           format_number(f.max_px) + " px (more than 0.01)");
    meta_set(meta, "rpc_fit_view" + std::to_string(v + 1) + "_px", "rms " + format_number(f.rms_px) + ", max " + format_number(f.max_px));
    out.push_back(f.model);
  }
  return out;
}

void write_synth_rpc_files(const std::string& dir, const std::vector<ImageRef>& images, const Meta& meta,
                           const std::vector<RpcModel>& rpcs, const std::map<int, ImageBias>& bias) {
  const int N = static_cast<int>(images.size());
  for (int v = 0; v < N; ++v) write_rpc_txt(dir + "/view" + std::to_string(v + 1) + "_rpc.txt", rpcs[v]);
  BiasTable bt;
  bt.images = images;
  bt.meta = meta;
  meta_set(bt.meta, "bias", "injected into the written RPCs: truth pixel = written RPC projection + (a0 + a1 x + a2 y, "
                            "b0 + b1 x + b2 y) (pixels, x y of the written projection)");
  for (int v = 0; v < N; ++v) {
    auto it = bias.find(v);
    bt.bias.push_back(it == bias.end() ? ImageBias{} : it->second);
  }
  save_bias_table(dir + "/truth.bias", bt);
}
// Files view<K>.tif and view<K>_rpc.txt with K > views in dir: an older scene's, removed when this run commits.
void remove_stale_views(const std::string& dir, int views) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() < 5 || name.compare(0, 4, "view") != 0) continue;
    size_t i = 4;
    while (i < name.size() && std::isdigit(static_cast<unsigned char>(name[i]))) ++i;
    const std::string rest = name.substr(i);
    if (i == 4 || i > 8 || (rest != ".tif" && rest != "_rpc.txt")) continue;
    if (std::stoi(name.substr(4, i - 4)) > views) remove_on_commit(dir + "/" + name);
  }
}

std::string fixed(double v, int decimals) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(decimals);
  os << v;
  return os.str();
}

// Description of view v for the TIFF and the metadata.
std::string view_text(const SynthScene& scene, int v) {
  if (!scene.is_block()) return v == 0 ? "forward" : v == 1 ? "nadir" : "backward";
  const Eigen::Vector3d a = scene.view_angles(v);
  const int k = synth_views_per_date(scene.params()), i = scene.index_in_date(v);
  const std::string kind = k == 1 ? "nadir" : i == 0 ? "forward" : i == k - 1 ? "backward" : k == 3 ? "nadir" : "middle";
  return "date " + std::to_string(scene.date_of(v) + 1) + " view " + std::to_string(i + 1) + " " + kind + ": along-track " +
         fixed(a[0], 2) + " deg, cross-track " + fixed(a[1], 2) + " deg, roll " + fixed(a[2], 2) + " deg";
}
}  // namespace

void write_synth_scene(const SynthScene& scene, const std::string& dir, const SynthWriteOptions& opt) {
  const SynthParams& p = scene.params();
  // Truth first: it is quick and may fail (too few visible points) before anything is written.
  const SynthTruth truth = synth_truth_points(scene, p.points);
  create_output_dir(dir);  // removed again if the run fails

  Meta meta;
  meta_set(meta, "generator", "tp-synth");
  meta_set(meta, "seed", std::to_string(p.seed));
  meta_set(meta, "size", std::to_string(p.size));
  meta_set(meta, "relief", format_number(p.relief));
  meta_set(meta, "gsd", format_number(p.gsd));
  meta_set(meta, "camera", p.camera);
  meta_set(meta, "points", std::to_string(p.points));
  meta_set(meta, "noise", format_number(p.noise));
  meta_set(meta, "supersample", std::to_string(p.supersample));
  if (synth_has_conditions(p))  // radiometric only (synth_conditions.hpp): the truth is unchanged
    meta_set(meta, "conditions", "second_date " + format_number(p.date2) + " clouds " + format_number(p.clouds) + " water " +
                                     format_number(p.water) + " nodata_band " + format_number(p.nodata) +
                                     " (view 1 the reference date; DN 0 = nodata)");
  if (!p.cross_track.empty()) {  // given by --cross-track (else seeded, and no line, as before)
    std::string ct;
    for (double c : p.cross_track) ct += (ct.empty() ? "" : ",") + format_number(c);
    meta_set(meta, "cross_track_deg", ct);
  }
  const int N = scene.views();
  if (scene.is_block()) {
    const int k = synth_views_per_date(p);
    meta_set(meta, "block", std::to_string(p.dates) + " dates x " + std::to_string(k) + " views; view v is view ((v - 1) mod " +
                                std::to_string(k) + ") + 1 of date floor((v - 1) / " + std::to_string(k) + ") + 1");
    for (int v = 0; v < N; ++v) meta_set(meta, "view" + std::to_string(v + 1), view_text(scene, v));
    std::string ov;
    for (const auto& nb : synth_neighbours(scene))
      ov += (ov.empty() ? "" : ", ") + std::to_string(nb.first + 1) + "-" + std::to_string(nb.second + 1) + " " +
            fixed(synth_footprint_overlap(scene, nb.first, nb.second), 2);
    meta_set(meta, "footprint_overlap", ov + " (neighbouring views: area of the intersection of their footprints on Z = 0 "
                                             "over the smaller footprint)");
  }
  meta_set(meta, "scene", "ground square [0, " + format_number(scene.scene_size()) +
                              "] m x [0, same] m; X east, Y north, Z up (m)");

  std::vector<ImageRef> images;
  for (int v = 0; v < N; ++v) images.push_back({"view" + std::to_string(v + 1) + ".tif", p.size, p.size});
  std::vector<RpcModel> rpcs;
  std::optional<SynthGeoFrame> geo;
  if (opt.rpc) {
    geo.emplace(scene, opt.origin);
    rpcs = synth_rpc_models(scene, *geo, opt.rpc_bias, meta);
  }

  // Views: strips rendered by worker threads in batches, written in order (bounded memory).
  const long W = p.size, rows = std::max(1L, opt.strip_rows);
  int threads = opt.threads > 0 ? opt.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const long strips = (W + rows - 1) / rows;
  Progress progress("rendering", strips * N);
  for (int v = 0; v < N; ++v) {
    std::string desc = "tp-synth view " + std::to_string(v + 1) + " (" + view_text(scene, v) + "); seed " + std::to_string(p.seed) + "; 12-bit DN = gain * radiance + offset + noise; gain " +
                       format_number(scene.gain(v)) + ", offset " + format_number(scene.offset(v));
    TiffWriterU16 writer(dir + "/" + images[v].path, W, W, {{"ImageDescription", desc},
                                                                 // fixed, so that the same seed gives the same bytes
                                                                 {"DateTime", "2000:01:01 00:00:00"}});
    if (opt.rpc) writer.set_rpc_tag(rpc_tag_values(rpcs[v]));
    const long batch = 2L * threads;
    std::vector<std::vector<uint16_t>> buf(static_cast<size_t>(std::min(batch, strips)));
    for (long s0 = 0; s0 < strips; s0 += batch) {
      const long nb = std::min(batch, strips - s0);
      parallel_for(static_cast<size_t>(nb), threads, [&](size_t k) {
        const long y0 = (s0 + static_cast<long>(k)) * rows, h = std::min(rows, W - y0);
        buf[k].resize(static_cast<size_t>(h) * W);
        scene.sensor_rows(v, y0, h, buf[k].data());  // render_rows, blurred where the view's sensor blurs (synth_sensor.hpp)
        progress.add();
      });
      for (long k = 0; k < nb; ++k) {
        const long y0 = (s0 + k) * rows, h = std::min(rows, W - y0);
        writer.write_rows(y0, h, buf[k].data());
      }
    }
    writer.close();
  }
  progress.done();

  // Truth tracks with the ground point as extra columns X Y Z.
  Tracks tr;
  tr.images = images;
  tr.meta = meta;
  const std::string seen_by = scene.is_block() ? "visible in two views or more (nan nan: not seen by that view)" : "visible in all three views";
  meta_set(tr.meta, "truth", "noise-free projections of ground points " + seen_by + "; X Y Z in metres");
  if (scene.is_block()) {
    std::vector<long> by(static_cast<size_t>(N) + 1, 0);
    for (Eigen::Index i = 0; i < truth.xy.rows(); ++i) {
      int c = 0;
      for (int v = 0; v < N; ++v) c += !std::isnan(truth.xy(i, 2 * v));
      ++by[static_cast<size_t>(c)];
    }
    std::string t;
    for (int c = 2; c <= N; ++c)
      if (by[c]) t += (t.empty() ? "" : " ") + std::to_string(c) + ":" + std::to_string(by[c]);
    meta_set(tr.meta, "tracks_by_views", t);
  }
  tr.xy = truth.xy;
  tr.id.resize(truth.xy.rows());
  for (Eigen::Index i = 0; i < truth.xy.rows(); ++i) tr.id[i] = i + 1;
  tr.extra.names = {"X", "Y", "Z"};
  tr.extra.values = truth.ground;
  if (opt.rpc) {
    meta_set(tr.meta, "truth", "noise-free projections of ground points " + seen_by + "; X Y Z in metres "
                               "(local frame); lon lat in degrees WGS84, h in metres above the ellipsoid");
    tr.extra.names = {"X", "Y", "Z", "lon", "lat", "h"};
    tr.extra.values.resize(truth.ground.rows(), 6);
    for (Eigen::Index i = 0; i < truth.ground.rows(); ++i) {
      Eigen::Vector3d g = truth.ground.row(i).transpose();
      tr.extra.values.block<1, 3>(i, 0) = g.transpose();
      tr.extra.values.block<1, 3>(i, 3) = geo->to_llh(g).transpose();
    }
    write_synth_rpc_files(dir, images, meta, rpcs, opt.rpc_bias);
    write_geotiff_grid(dir + "/truth.dem.tif", synth_dem(scene, *geo, 1.0));
  } else {
    for (int v = 0; v < N; ++v) remove_on_commit(dir + "/view" + std::to_string(v + 1) + "_rpc.txt");
    remove_on_commit(dir + "/truth.bias");
    remove_on_commit(dir + "/truth.dem.tif");
  }
  save_tracks(dir + "/truth.tracks", tr);

  Cameras cams;
  cams.images = images;
  cams.meta = meta;
  meta_set(cams.meta, "cameras", scene.is_block() ? "x ~ P [X Y Z 1]^T: ground metres (local frame) to pixels; views as in block"
                                                  : "x ~ P [X Y Z 1]^T: ground metres (local frame) to pixels; view 1 forward, 2 nadir, 3 backward");
  for (int v = 0; v < N; ++v) cams.P.push_back(scene.camera(v));
  save_cameras(dir + "/truth.cameras", cams);

  if (p.camera == "affine" && N == 3) {
    Trifocal tf;
    tf.images = images;
    tf.meta = meta;
    meta_set(tf.meta, "method", "exact, from the truth cameras (H&Z T_i = a_i b_4^T - a_4 b_i^T, P1 H = [I | 0])");
    tf.T = trifocal_from_cameras(scene.camera(0), scene.camera(1), scene.camera(2));
    save_trifocal(dir + "/truth.trifocal", tf);
  } else {
    remove_on_commit(dir + "/truth.trifocal");  // an older affine scene's tensor is not this scene's truth
  }
  remove_stale_views(dir, N);
  save_params(dir + "/scene.params", p);
}

}  // namespace tpkit
