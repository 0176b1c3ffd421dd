// Rendering and writing of the tp-synth triplet (synth_scene.hpp: SynthScene::render_rows,
// write_synth_scene; synth_render.hpp: the exact per-sample reference renderer).
//
// Pixel response (both renderers): the mean radiance over n x n samples at offsets (k + 0.5) / n - 0.5
// from the pixel centre (box pixel response; n = --supersample, default 4), each sample on the first
// terrain intersection of its viewing ray.
//
// SynthScene::render_rows (the fast renderer) evaluates the radiance, the costly part, on a node lattice
// only: nodes (I, J) at image position (I / m, J / m) (pixel (x, y) is node (m x, m y)), m = ceil(n / 2)
// (n = 4: m = 2, four nodes per pixel instead of 16 samples). A sample's radiance is the Catmull-Rom
// (bicubic, interpolating) interpolation of the node radiances around it; the n x n samples of a pixel
// are then one fixed separable filter of the node lattice (node_filter: n = 4 gives the 1-D weights
// -3/128, 1/4, 35/64, 1/4, -3/128 on node offsets -2..2), so nothing is evaluated per sample. The
// texture's shortest wavelengths are >= 2 gsd and its edges smoothsteps of width gsd (synth_texture.hpp),
// i.e. >= 4 nodes per period, where Catmull-Rom keeps > 90 % of the amplitude.
// Geometry of the nodes: exact casts (grid traversal + bracketing, synth_terrain.hpp) on a coarse lattice
// every kCoarsePx = 4 pixels; a node inside a coarse cell whose four corner hits are consistent (no
// occlusion edge) is found by Newton (to 1 cm steps: ~1e-4 m) from the bilinear interpolation of the
// corner ray parameters plus the linear extrapolation of the two previous nodes' offsets from theirs
// (1.14 Newton steps a node on the default scene), every other node by an exact cast; an occluded sliver
// narrower than the coarse cell can be missed. Each node row is computed left to right from the coarse
// lattice only, so a pixel does not depend on strip or thread.
// Where the time goes: each node's Newton start waits for its left neighbour's result, so the rows of a
// group of four are stepped in lockstep (SynthTerrain::refine_lanes, on each terrain cell's power-basis
// polynomial, shared between the group's rays): four independent chains the CPU overlaps. The radiances
// of the group follow in one call (SynthScene::radiance_n: layout, then noises and shading in passes);
// the texture keeps what it drew for the last block (its type and road lines), parcel, lot and noise
// cell, inline in one loop (synth_texture.cpp); a row's sensor noise goes in passes too (DnFinish::row).
// These inner loops are compiled for the x86-64 baseline and for AVX2, the loader picking one
// (core/cpu_dispatch.hpp: the same IEEE operations, no FMA). All of it gives the pixels of the straightforward
// loop (bench_synth --compare: 0 DN), only faster.
// Agreement, measured (bench_synth --agreement 1024 64, default scene, noise 0, the middle 64 rows of
// each view): fast - exact reference 2.18 DN RMS (max 52 DN, at roof rims and hedges) at n = 4, 0.26 DN
// at n = 8; the exact 4 x 4 and 8 x 8 renderings differ by 0.75 DN RMS, the sensor noise is 2 DN. The
// interpolation smooths the finest texture a little; bench_match_accuracy's triplet errors on the
// synthetic truth stay as they were (man/tp-synth.1, PERFORMANCE). Radiance evaluations a pixel: 4
// nodes instead of 16 samples. Speed, each renderer against the one before it back to back on the shared
// 2-core machine: the first renderer 3.5 us a pixel a view; 0.72 us (BM_RenderStrip/0, 32 x 1024 px:
// 23.6 ms); 0.42 us (13.7 ms, the lockstep rows and the texture's memory); 0.34 us, 0.82 times that
// (12.7 ms against 15.5 at a heavier load; bench_synth --agreement, noise 0: 372 against 448 ms a
// megapixel a view), i.e. 10 times the first renderer.
#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/cpu_dispatch.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/rpc/rpc_bias.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/synth/synth_camera.hpp"
#include "tpkit/synth/synth_conditions.hpp"
#include "tpkit/synth/synth_noise.hpp"
#include "tpkit/synth/synth_render.hpp"
#include "tpkit/synth/synth_scene.hpp"
#include "tpkit/synth/synth_structures.hpp"
#include "tpkit/synth/synth_terrain.hpp"

namespace tpkit {

namespace {
// synth_finish_dn with what depends on the view only worked out once (a rendered row finishes its pixels
// with one of these): the same values.
class DnFinish {
 public:
  DnFinish(const SynthScene& scene, int view)
      : p_(scene.params()), view_(view), gain_(scene.gain(view)), offset_(scene.offset(view)),
        noise_seed_(synth::hash(p_.seed, 0x401e, view)), conditions_(synth_has_conditions(p_)) {}
  double operator()(long x, long y, double radiance) const {
    return finish(x, gain_ * radiance + offset_ + (p_.noise > 0 ? p_.noise * synth::normal(synth::hash(noise_seed_, y, x)) : 0.0));
  }
  // Row y, x < W: out[x] = (*this)(x, y, radiance[x]), the noise's stages each in a pass over the row
  // (short independent iterations the CPU overlaps; a whole pixel's chain is too long for it to).
  void row(long y, long W, const double* radiance, uint16_t* out) {
    if (!(p_.noise > 0)) {
      for (long x = 0; x < W; ++x) out[x] = static_cast<uint16_t>(finish(x, gain_ * radiance[x] + offset_));
      return;
    }
    u1_.resize(static_cast<size_t>(W));
    u2_.resize(static_cast<size_t>(W));
    for (long x = 0; x < W; ++x) synth::normal_uniforms(synth::hash(noise_seed_, y, x), u1_[x], u2_[x]);
    for (long x = 0; x < W; ++x) u1_[x] = synth::normal_from(u1_[x], u2_[x]);
    for (long x = 0; x < W; ++x) out[x] = static_cast<uint16_t>(finish(x, gain_ * radiance[x] + offset_ + p_.noise * u1_[x]));
  }

 private:
  // The DN from gain * radiance + offset + noise: the conditions, then rounded and clamped.
  double finish(long x, double dn) const {
    if (conditions_) dn = synth_condition_dn(p_, view_, x, dn);
    // std::clamp(std::round(dn), 0, 4095) without round's library call: clamped first (the same result),
    // then rounded half away from zero by its integer part (exact below 2^52); nan (never made) gives 0.
    if (!(dn > 0)) return 0;
    dn = std::min(dn, 4095.0);
    const double whole = static_cast<double>(static_cast<long>(dn));
    return whole + static_cast<double>(dn - whole >= 0.5);  // (no branch: half the pixels round up)
  }

  const SynthParams& p_;
  int view_;
  double gain_, offset_;
  uint64_t noise_seed_;
  bool conditions_;
  std::vector<double> u1_, u2_;  // row()'s uniforms, then deviates
};

// Floor of a / b for b > 0.
long floor_div(long a, long b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Step of the coarse lattice of exact casts, pixels.
constexpr long kCoarsePx = 4;
}  // namespace

SynthNodeFilter synth_node_filter(int n) {
  SynthNodeFilter f;
  f.m = (n + 1) / 2;
  // Sample k at s = (k + 0.5) / n - 0.5 px = p nodes; Catmull-Rom weights of nodes i - 1 .. i + 2 (i = floor p).
  std::vector<double> acc(static_cast<size_t>(4 * f.m + 8), 0.0);
  const long c = 2 * f.m + 3;  // acc[c + k]: node offset k
  for (int k = 0; k < n; ++k) {
    const double p = ((k + 0.5) / n - 0.5) * f.m;
    const double fl = std::floor(p), t = p - fl, t2 = t * t, t3 = t2 * t;
    const double w[4] = {0.5 * (-t3 + 2 * t2 - t), 0.5 * (3 * t3 - 5 * t2 + 2), 0.5 * (-3 * t3 + 4 * t2 + t), 0.5 * (t3 - t2)};
    for (int q = 0; q < 4; ++q) acc[static_cast<size_t>(c + static_cast<long>(fl) - 1 + q)] += w[q] / n;
  }
  f.r = 0;
  for (long k = -c; k < static_cast<long>(acc.size()) - c; ++k)
    if (acc[static_cast<size_t>(c + k)] != 0) f.r = std::max(f.r, static_cast<int>(std::abs(k)));
  for (long k = -f.r; k <= f.r; ++k) f.w.push_back(acc[static_cast<size_t>(c + k)]);
  return f;
}

SynthNodeFilter synth_box_node_filter(int n) {
  SynthNodeFilter f;
  f.m = n;
  f.r = n - 1;
  f.w.assign(static_cast<size_t>(2 * f.r + 1), 0.0);
  for (int k = 0; k < n; ++k) f.w[static_cast<size_t>(f.r + k)] = 1.0 / n;
  return f;
}

double synth_finish_dn(const SynthScene& scene, int view, long x, long y, double radiance) {
  return DnFinish(scene, view)(x, y, radiance);
}

void synth_reference_rows(const SynthScene& scene, int view, long y0, long rows, uint16_t* out) {
  const long W = scene.params().size;
  const int ns = static_cast<int>(scene.params().supersample);
  const bool conditions = synth_has_conditions(scene.params());
  const bool structured = scene.has_structures();
  for (long j = 0; j < rows; ++j)
    for (long x = 0; x < W; ++x) {
      double sum = 0;
      for (int b = 0; b < ns; ++b)
        for (int a = 0; a < ns; ++a) {
          if (structured) {
            const auto s = scene.surface(view, x - 0.5 + (a + 0.5) / ns, y0 + j - 0.5 + (b + 0.5) / ns);
            if (s) sum += scene.surface_radiance(view, *s);
            continue;
          }
          const auto X = scene.ground_point(view, x - 0.5 + (a + 0.5) / ns, y0 + j - 0.5 + (b + 0.5) / ns);
          if (!X) continue;  // cannot happen inside the terrain grid: counts as black
          const Eigen::Vector2d g = scene.height_gradient(X->x(), X->y());
          sum += conditions ? synth_condition_radiance(scene, view, X->x(), X->y(), g) : scene.radiance(X->x(), X->y(), g);
        }
      out[static_cast<size_t>(j) * W + x] = static_cast<uint16_t>(synth_finish_dn(scene, view, x, y0 + j, sum / (ns * ns)));
    }
}

TPKIT_HOT void SynthScene::render_rows(int view, long y0, long rows, uint16_t* out) const {
  const long W = params().size;
  // Scenes with buildings and trees: walls, roof and crown edges and cast shadows are discontinuities that
  // the Catmull-Rom interpolation of nodes rings at; there the nodes are the samples themselves (the box
  // filter of synth_box_node_filter, node I at (I + 0.5) / n - 0.5 px), each on its exact surface.
  const bool structured = has_structures();
  const SynthNodeFilter flt = structured ? synth_box_node_filter(static_cast<int>(params().supersample))
                                         : synth_node_filter(static_cast<int>(params().supersample));
  const long m = flt.m, r = flt.r;
  const double shift = structured ? 0.5 / m - 0.5 : 0.0;  // node position I / m + shift (px)
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Nodes I in [I0, I1], J in [J0, J1] (image position (I / m, J / m)); coarse casts at multiples of kCoarse.
  const long kCoarse = kCoarsePx * m;  // in nodes
  const long I0 = -r, I1 = m * (W - 1) + r, J0 = m * y0 - r, J1 = m * (y0 + rows - 1) + r;
  const long NI = I1 - I0 + 1, NJ = J1 - J0 + 1;
  const long C0 = floor_div(I0, kCoarse), C1 = floor_div(I1, kCoarse) + 1;  // coarse columns
  const long R0 = floor_div(J0, kCoarse), R1 = floor_div(J1, kCoarse) + 1;  // coarse rows
  const long NC = C1 - C0 + 1;
  const SynthCamera& cam = camera_(view);  // rays as ray() gives them, inline
  const double z_top = z_top_();
  Eigen::Vector3d o, d;
  // Stage 1: exact casts on the coarse lattice (1 mm is plenty for a starting guess and the smoothness test).
  std::vector<double> tc(static_cast<size_t>((R1 - R0 + 1) * NC));
  for (long R = R0; R <= R1; ++R)
    for (long C = C0; C <= C1; ++C) {
      if (structured)
        cam.ray(static_cast<double>(C * kCoarse) / m + shift, static_cast<double>(R * kCoarse) / m + shift, z_top, o, d);
      else
        cam.ray(static_cast<double>(C * kCoarse) / m, static_cast<double>(R * kCoarse) / m, z_top, o, d);
      const auto t = terrain_().intersect(o, d, 1e-3);
      tc[static_cast<size_t>((R - R0) * NC + (C - C0))] = t ? *t : nan;
    }
  // Corner parameters of a smooth cell differ by a few pixel sizes per pixel at most; a larger jump means
  // an occlusion edge (or a grazing ray) inside the cell.
  const double jump = 6 * params().gsd * kCoarsePx;
  auto smooth = [&](double a, double b, double c, double e) {
    return std::isfinite(a) && std::isfinite(b) && std::isfinite(c) && std::isfinite(e) && std::abs(b - a) < jump &&
           std::abs(e - c) < jump && std::abs(c - a) < jump && std::abs(e - b) < jump;
  };
  // Stage 2: node radiances, in groups of kRowGroup node rows: first the ground points of the group, each
  // row left to right, the rows' Newton chains interleaved (they are independent: the CPU overlaps their
  // latencies), then the radiances of the group's nodes.
  const bool conditions = synth_has_conditions(params());
  // (buffers without the zeroing of a std::vector: every element is written before it is read)
  const std::unique_ptr<double[]> node(new double[static_cast<size_t>(NI * NJ)]);
  struct Row {
    const double* c0;  // coarse parameters above and below the row
    const double* c1;
    double fy;
    // Offsets of the two previous nodes' Newton results from their bilinear starts (nan: none): the start
    // is the bilinear interpolation plus their linear extrapolation.
    double res1, res2;
  };
  constexpr long kRowGroup = SynthTerrain::kLanes;
  // The group's ground points and terrain gradients, row k at k * NI; hx = nan: the ray missed.
  const size_t nh = static_cast<size_t>(kRowGroup * NI);
  const std::unique_ptr<double[]> hx(new double[nh]), hy(new double[nh]), hgx(new double[nh]), hgy(new double[nh]);
  // Scenes with buildings and trees: each node's surface is the nearer of the terrain point above and the
  // first structure the ray enters before it (exact: closed-form, synth_structures.hpp), shaded with the
  // view's sun and its cast shadows (surface_radiance).
  std::vector<SynthSurface> surf(structured ? nh : 0);
  for (long Jg = J0; Jg <= J1; Jg += kRowGroup) {
    const long nk = std::min(kRowGroup, J1 - Jg + 1);
    Row rw[kRowGroup];
    SynthTerrain::Patch patch[kRowGroup];  // per row: the terrain cell of its last Newton step
    bool missed = false;
    for (long k = 0; k < nk; ++k) {
      const long J = Jg + k, R = floor_div(J, kCoarse);
      rw[k].c0 = &tc[static_cast<size_t>((R - R0) * NC)];
      rw[k].c1 = rw[k].c0 + NC;
      rw[k].fy = static_cast<double>(J - R * kCoarse) / kCoarse;
      rw[k].res1 = rw[k].res2 = nan;
    }
    // Coarse cell C of the rows' nodes I (its corners and whether it is smooth: per row, once a cell).
    long C = floor_div(I0, kCoarse) - 1;
    double corner[kRowGroup][4];
    bool cell_smooth[kRowGroup];
    for (long I = I0; I <= I1; ++I) {
      if (I >= (C + 1) * kCoarse) {
        C = floor_div(I, kCoarse);
        for (long k = 0; k < nk; ++k) {
          const Row& w = rw[k];
          double* q = corner[k];
          q[0] = w.c0[C - C0], q[1] = w.c0[C - C0 + 1], q[2] = w.c1[C - C0], q[3] = w.c1[C - C0 + 1];
          cell_smooth[k] = smooth(q[0], q[1], q[2], q[3]);
        }
      }
      // Node I of every row of the group: Newton from the start where the cell is smooth (t nan: not)...
      Eigen::Vector3d o[kRowGroup], d[kRowGroup];
      Eigen::Vector2d grad[kRowGroup];
      double t[kRowGroup], bil[kRowGroup];
      const double fx = static_cast<double>(I - C * kCoarse) / kCoarse;
      for (long k = 0; k < nk; ++k) {
        Row& w = rw[k];
        if (structured)
          cam.ray(static_cast<double>(I) / m + shift, static_cast<double>(Jg + k) / m + shift, z_top, o[k], d[k]);
        else
          cam.ray(static_cast<double>(I) / m, static_cast<double>(Jg + k) / m, z_top, o[k], d[k]);
        t[k] = bil[k] = nan;
        if (cell_smooth[k]) {
          const double t00 = corner[k][0], t10 = corner[k][1], t01 = corner[k][2], t11 = corner[k][3];
          const double fy = w.fy;
          bil[k] = (1 - fy) * ((1 - fx) * t00 + fx * t10) + fy * ((1 - fx) * t01 + fx * t11);
          const double carry = std::isfinite(w.res2) ? 2 * w.res1 - w.res2 : std::isfinite(w.res1) ? w.res1 : 0;
          t[k] = bil[k] + carry;
        }
      }
      // ... until a step is below 1 cm: the position error is then ~ (curvature / slope) x step^2, below
      // 1e-4 m for the terrains made here; the gradient of its last evaluation shades ...
      terrain_().refine_lanes(static_cast<int>(nk), o, d, t, 1e-2, grad, patch);
      for (long k = 0; k < nk; ++k) {
        Row& w = rw[k];
        if (!std::isnan(bil[k])) {
          w.res2 = w.res1;
          w.res1 = t[k] - bil[k];  // nan where Newton failed
        } else {
          w.res1 = w.res2 = nan;
        }
        // ... else an exact cast.
        const size_t h = static_cast<size_t>(k * NI + (I - I0));
        if (structured) {
          double tt = t[k];
          if (std::isnan(tt)) {
            const auto te = terrain_().intersect(o[k], d[k]);
            tt = te ? *te : std::numeric_limits<double>::infinity();
            if (te) {
              const Eigen::Vector3d X = o[k] + tt * d[k];
              terrain_().height(X.x(), X.y(), &grad[k]);
            }
          }
          SynthStructureHit sh;
          SynthSurface& sf = surf[h];
          if (structures().intersect(o[k], d[k], 0, tt, &sh)) {
            sf.X = o[k] + sh.t * d[k];
            sf.normal = sh.normal;
            sf.kind = sh.kind;
            sf.id = sh.id;
          } else if (std::isinf(tt)) {
            hx[h] = nan;
            missed = true;
            continue;
          } else {
            sf.X = o[k] + tt * d[k];
            sf.normal = Eigen::Vector3d(-grad[k].x(), -grad[k].y(), 1).normalized();
            sf.kind = SynthStructures::kTerrain;
            sf.id = -1;
          }
          hx[h] = sf.X.x();
          hy[h] = sf.X.y();
          continue;
        }
        if (std::isnan(t[k])) {
          const auto te = terrain_().intersect(o[k], d[k]);
          if (!te) {
            hx[h] = nan;  // a ray that misses cannot happen inside the terrain grid: black
            missed = true;
            continue;
          }
          t[k] = *te;
          const Eigen::Vector3d X = o[k] + t[k] * d[k];
          terrain_().height(X.x(), X.y(), &grad[k]);
        }
        const Eigen::Vector3d X = o[k] + t[k] * d[k];
        hx[h] = X.x();
        hy[h] = X.y();
        hgx[h] = grad[k].x();
        hgy[h] = grad[k].y();
      }
    }
    double* out = &node[static_cast<size_t>((Jg - J0) * NI)];
    if (structured) {
      for (long i = 0; i < nk * NI; ++i)
        out[i] = std::isnan(hx[static_cast<size_t>(i)]) ? 0 : surface_radiance(view, surf[static_cast<size_t>(i)]);
      continue;
    }
    if (!conditions && !missed) {
      radiance_n(nk * NI, hx.get(), hy.get(), hgx.get(), hgy.get(), out);
      continue;
    }
    for (long i = 0; i < nk * NI; ++i) {
      const size_t h = static_cast<size_t>(i);
      if (std::isnan(hx[h])) {
        out[i] = 0;
        continue;
      }
      const Eigen::Vector2d g(hgx[h], hgy[h]);
      out[i] = conditions ? synth_condition_radiance(*this, view, hx[h], hy[h], g) : radiance(hx[h], hy[h], g);
    }
  }
  // Stage 3: the pixel filter, rows then columns: pixel (x, y) = sum_ij w_i w_j node(m x + i, m y + j), each
  // sum from 0 in the order of k, tap by tap over a whole row (loops over x that vectorize).
  const std::unique_ptr<double[]> hrow(new double[static_cast<size_t>(NJ * W)]);
  for (long J = 0; J < NJ; ++J) {
    double* h = &hrow[static_cast<size_t>(J * W)];
    const double* p = &node[static_cast<size_t>(J * NI)];  // node I = m x - r at p[m x]
    std::fill(h, h + W, 0.0);
    for (long k = 0; k <= 2 * r; ++k) {
      const double wk = flt.w[static_cast<size_t>(k)];
      for (long x = 0; x < W; ++x) h[x] += wk * p[m * x + k];
    }
  }
  DnFinish finish(*this, view);
  std::vector<double> col(static_cast<size_t>(W));
  for (long j = 0; j < rows; ++j) {
    std::fill(col.begin(), col.end(), 0.0);
    for (long k = 0; k <= 2 * r; ++k) {
      const double wk = flt.w[static_cast<size_t>(k)];
      const double* h = &hrow[static_cast<size_t>((m * j + k) * W)];
      for (long x = 0; x < W; ++x) col[static_cast<size_t>(x)] += wk * h[x];
    }
    finish.row(y0 + j, W, col.data(), out + static_cast<size_t>(j) * W);
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
  if (scene.has_structures())  // geometric (synth_structures.hpp): the truth goes through them
    meta_set(meta, "structures", "buildings " + format_number(p.buildings) + " trees " + format_number(p.trees) + ": " +
                                     std::to_string(scene.structures().buildings()) + " buildings, " +
                                     std::to_string(scene.structures().trees()) +
                                     " trees; truth points on the surface (ground, roofs, crowns), hidden where a wall "
                                     "or crown stands between them and a view; truth.dem.tif is the surface model");
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
    // Batch b is rendered while one worker writes (and deflates) batch b - 1: item 0 of each parallel_for.
    const long batch = 2L * threads;
    std::vector<std::vector<uint16_t>> buf[2];
    buf[0].resize(static_cast<size_t>(std::min(batch, strips)));
    buf[1].resize(buf[0].size());
    auto write_batch = [&](long s0, std::vector<std::vector<uint16_t>>& b) {
      for (long k = 0; k < batch && s0 + k < strips; ++k) {
        const long y0 = (s0 + k) * rows, h = std::min(rows, W - y0);
        writer.write_rows(y0, h, b[static_cast<size_t>(k)].data());
      }
    };
    for (long s0 = 0, b = 0; s0 < strips; s0 += batch, b ^= 1) {
      const long nb = std::min(batch, strips - s0);
      const size_t first = s0 > 0 ? 1 : 0;  // item 0: write the previous batch
      parallel_for(static_cast<size_t>(nb) + first, threads, [&](size_t item) {
        if (item < first) return write_batch(s0 - batch, buf[b ^ 1]);
        const size_t k = item - first;
        const long y0 = (s0 + static_cast<long>(k)) * rows, h = std::min(rows, W - y0);
        buf[b][k].resize(static_cast<size_t>(h) * W);
        scene.sensor_rows(v, y0, h, buf[b][k].data());  // render_rows, blurred where the view's sensor blurs (synth_sensor.hpp)
        progress.add();
      });
      if (s0 + batch >= strips) write_batch(s0, buf[b]);
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
