// Ground albedo of tp-synth (synth_texture.hpp).
#include "tpkit/synth/synth_texture.hpp"

#include <algorithm>
#include <cmath>

#include "tpkit/core/cpu_dispatch.hpp"
#include "tpkit/synth/synth_noise.hpp"

namespace tpkit {

using synth::hash;
using synth::lerp;
using synth::sin_turns;
using synth::smoothstep;
using synth::uniform;
using synth::value_noise;

namespace {
constexpr double kPi = 3.14159265358979323846;
// Weight 1 inside (signed distance sd > 0 inside), 0 outside, a smooth ramp of width w across sd = 0.
inline double inside(double sd, double w) { return smoothstep(-0.5 * w, 0.5 * w, sd); }
// Signed distance to an axis-aligned rectangle (centre cx, cy, half sizes hx, hy): positive inside.
inline double rect_sd(double x, double y, double cx, double cy, double hx, double hy) {
  const double qx = std::abs(x - cx) - hx, qy = std::abs(y - cy) - hy;
  const double ox = std::max(qx, 0.0), oy = std::max(qy, 0.0);
  // the length of (ox, oy); sqrt(x * x) is x exactly, so the square root only where both are positive
  const double out = oy == 0 ? ox : ox == 0 ? oy : std::sqrt(ox * ox + oy * oy);
  return -(out + std::min(std::max(qx, qy), 0.0));
}
// Partition of [0, L) into n cells with seeded random widths; returns the cell of x and the distance
// from x to the nearest cell boundary (0 and L included).
// The k-th 16-bit field of a hash as a uniform in [0, 1) (k = 0..3): several draws from one hash.
inline double b16(uint64_t h, int k) { return static_cast<double>((h >> (16 * k)) & 0xffff) * (1.0 / 65536); }
// The cell boundaries e[0] < .. < e[n - 1] = L of the partition (the widths' arithmetic of one pass).
struct Cuts {
  int n = 0;
  double e[8];
};
Cuts cuts(uint64_t s, int n, double L) {
  Cuts c;
  c.n = n;
  double w[8], total = 0;
  const uint64_t h0 = synth::mix64(s), h1 = n > 4 ? synth::mix64(s ^ 0x51ed27ULL) : 0;
  for (int k = 0; k < n; ++k) total += (w[k] = 0.5 + b16(k < 4 ? h0 : h1, k & 3));
  double b = 0;
  for (int k = 0; k < n; ++k) b = c.e[k] = (k == n - 1) ? L : b + L * w[k] / total;
  return c;
}
inline int partition(const Cuts& c, double x, double* dist) {
  double b = 0;
  for (int k = 0; k < c.n; ++k) {
    const double e = c.e[k];
    if (x < e || k == c.n - 1) {
      *dist = std::min(x - b, e - x);
      return k;
    }
    b = e;
  }
  *dist = 0;
  return 0;
}
// What farmland() draws per block (its parcels).
struct FarmBlock {
  bool valid = false;
  uint64_t seed = 0;
  int64_t bi = 0, bj = 0;
  double block = 0;
  Cuts strips;            // partition of u into strips
  uint64_t sh[4] = {};    // per strip: its hash
  Cuts parcels[4];        // per strip: partition of v into parcels
};
// What was drawn for the last key (a seed, two integers and the gsd): draw() runs when the key changes.
template <class T>
struct Kept {
  bool valid = false;
  uint64_t seed = 0;
  int64_t a = 0, b = 0;
  double gsd = 0;
  T v{};
};
template <class T, class Draw>
inline const T& kept(Kept<T>& k, uint64_t seed, int64_t a, int64_t b, double gsd, Draw draw) {
  if (!k.valid || k.a != a || k.b != b || k.seed != seed || k.gsd != gsd) {
    k.v = draw();
    k.valid = true;
    k.seed = seed;
    k.a = a;
    k.b = b;
    k.gsd = gsd;
  }
  return k.v;
}
// A parcel of farmland() (drawn from its hash ph and the gsd).
struct Parcel {
  uint64_t ph2 = 0;         // mix64(ph): the second draw, the rough field's noise seed
  double a = 0;             // base albedo
  bool crop = false;        // crop rows, else a rough field
  double dx = 0, dy = 0, wavelength = 0, amp = 0;  // crop rows: direction, dn * period, amplitude
  double il = 0;            // rough field: 1 / noise scale
};
// A lot of urban() (drawn from its hash h).
struct Lot {
  bool park = false;
  double cx = 0, cy = 0, hx = 0, hy = 0;  // building footprint: centre, half sizes
  double bh = 0, roof = 0;                // building height, roof albedo
};
// A road line of albedo() (drawn from its hash).
struct Road {
  bool present = false;
  double half = 0, asphalt = 0;
  uint64_t noise_seed = 0;
};
// Road line k of axis 0 (u = k B) or 1 (v = k B), from the texture's seed.
Road draw_road(uint64_t seed, int axis, int64_t k) {
  Road c;
  const uint64_t rh = hash(seed, 40 + axis, k);
  c.present = synth::unit(rh) <= 0.45;
  c.half = 3 + 3 * synth::unit(hash(rh, 1));
  c.asphalt = 0.2 + 0.25 * synth::unit(hash(rh, 2));
  c.noise_seed = hash(rh, 3);
  return c;
}
// What layout() draws for a block (bi, bj): its type's hash and the four road lines along its sides
// (road[axis][e]: line bi + e of axis 0, bj + e of axis 1), one memo test a point for all of them.
struct BlockLines {
  uint64_t type = 0;
  Road road[2][2];
};
// What albedo() draws from hashes, kept per thread for the last block, parcel, lot, road and value-noise
// cell it visited: neighbouring samples nearly always share them (the same values as drawing them afresh).
struct AlbedoMemo {
  FarmBlock farm;
  Kept<BlockLines> block;
  Kept<Lot> lot;
  Kept<Parcel> parcel;
  synth::NoiseCell pavement, crown[2], field, asphalt, large, fine;
};
AlbedoMemo& memo() {
  thread_local AlbedoMemo m;
  return m;
}
}  // namespace

SynthTexture::SynthTexture(uint64_t seed, double gsd, double sun_azimuth, double sun_elevation)
    : seed_(hash(seed, 0x7e47)), gsd_(gsd) {
  const int streams[5] = {20, 30, 31, 50, 51};
  for (int k = 0; k < 5; ++k) noise_seed_[k] = hash(seed_, streams[k]);
  ew_ = std::max(gsd_, 0.3);
  inv_block_ = 1 / block_;
  inv_crown_ = 1 / std::max(5.0, 3 * gsd_);
  inv_fine_ = 1 / std::max(1.0, 2 * gsd_);
  const double a = kPi * (0.05 + 0.4 * uniform(seed_, 1));
  ca_ = std::cos(a);
  sa_ = std::sin(a);
  ou_ = block_ * uniform(seed_, 2);
  ov_ = block_ * uniform(seed_, 3);
  // Sun direction in the layout frame (u, v) = rotation(X, Y), per metre of building height.
  const double sx = std::cos(sun_azimuth), sy = std::sin(sun_azimuth);
  const double len = 1 / std::tan(sun_elevation);
  sun_u_ = len * (ca_ * sx + sa_ * sy);
  sun_v_ = len * (-sa_ * sx + ca_ * sy);
}

[[gnu::always_inline]] inline double SynthTexture::farmland(int64_t bi, int64_t bj, double lu, double lv, double u, double v) const {
  AlbedoMemo& mm = memo();
  FarmBlock& fb = mm.farm;
  if (!fb.valid || fb.seed != seed_ || fb.bi != bi || fb.bj != bj || fb.block != block_) {
    const uint64_t bh = hash(seed_, 10, bi, bj);
    fb.strips = cuts(hash(bh, 1), 2 + static_cast<int>(bh % 3), block_);
    for (int k = 0; k < fb.strips.n; ++k) {
      fb.sh[k] = hash(bh, 2, k);
      fb.parcels[k] = cuts(hash(fb.sh[k], 3), 2 + static_cast<int>(fb.sh[k] % 4), block_);
    }
    fb.valid = true;
    fb.seed = seed_;
    fb.bi = bi;
    fb.bj = bj;
    fb.block = block_;
  }
  double d1, d2;
  const int s = partition(fb.strips, lu, &d1);
  const uint64_t sh = fb.sh[s];
  const int p = partition(fb.parcels[s], lv, &d2);
  const Parcel& pc = kept(mm.parcel, sh, p, 0, gsd_, [&] {
    Parcel c;
    const uint64_t ph = hash(sh, 4, p);
    c.ph2 = synth::mix64(ph);
    c.a = 0.15 + 0.5 * b16(ph, 0);
    c.crop = b16(ph, 1) < 0.6;
    if (c.crop) {
      // Crop rows: stripes at a parcel-specific orientation and period (>= 3 gsd).
      c.dx = b16(ph, 2) - 0.5;
      c.dy = b16(ph, 3) * 0.5 + 1e-3;
      const double dn = std::sqrt(c.dx * c.dx + c.dy * c.dy);
      c.wavelength = dn * std::max(2.5 + 6 * b16(c.ph2, 0), 3 * gsd_);
      c.amp = 0.04 + 0.1 * b16(c.ph2, 1);
    } else {
      // Rough fields: blotchy noise.
      c.il = 1 / std::max(4 + 8 * b16(c.ph2, 2), 3 * gsd_);
    }
    return c;
  });
  double a = pc.a;
  if (pc.crop)
    a += pc.amp * sin_turns((u * pc.dx + v * pc.dy) / pc.wavelength);
  else
    a += 0.08 * value_noise(pc.ph2, u * pc.il, v * pc.il, mm.field);
  // Dark hedges (1 m half width) along every parcel boundary.
  const double d = std::min(d1, d2);
  return lerp(0.1, a, inside(d - 1.0, ew_));
}

[[gnu::always_inline]] inline double SynthTexture::urban(int64_t bi, int64_t bj, double lu, double lv, double u, double v) const {
  const double lot = block_ / 4;
  const double inv_lot = 4 * inv_block_;
  const int64_t li = synth::floor_int(lu * inv_lot), lj = synth::floor_int(lv * inv_lot);
  // In the lot, [0, 60): footprint + shadow stay >= 3 m inside it (30 + 5 + 16 + 5.6 < 60).
  const double x = lu - li * lot, y = lv - lj * lot;
  AlbedoMemo& mm = memo();
  double a = 0.33 + 0.05 * value_noise(noise_seed_[0], u * (1.0 / 3), v * (1.0 / 3), mm.pavement);
  const int64_t ki = bi * 8 + li, kj = bj * 8 + lj;
  const Lot& lt = kept(mm.lot, seed_, ki, kj, block_, [&] {
    Lot c;
    const uint64_t h = hash(seed_, 21, ki, kj);
    c.park = synth::unit(h) > 0.85;
    const uint64_t h2 = synth::mix64(h);
    c.cx = lot / 2 + 5 * (2 * b16(h2, 0) - 1);
    c.cy = lot / 2 + 5 * (2 * b16(h2, 1) - 1);
    c.hx = 6 + 10 * b16(h2, 2);
    c.hy = 5 + 10 * b16(h2, 3);
    c.bh = 3 + 5 * b16(h, 1);  // building height (m); shadow |sun| * bh <= 6 m
    c.roof = 0.3 + 0.5 * b16(h, 2);
    return c;
  });
  if (lt.park) {
    // A small park: trees.
    return lerp(a, woodland(u, v), inside(std::min(std::min(x, lot - x), std::min(y, lot - y)) - 3, ew_));
  }
  const double cx = lt.cx, cy = lt.cy, hx = lt.hx, hy = lt.hy, bh = lt.bh;
  // Cast shadow: the footprint moved away from the sun, darkening the pavement.
  const double sd_shadow = rect_sd(x, y, cx - sun_u_ * bh, cy - sun_v_ * bh, hx, hy);
  a *= 1 - 0.55 * inside(sd_shadow, ew_);
  // Gabled roof: ridge along the longer side, the two halves lit differently.
  const double roof = lt.roof;
  const bool along_x = hx > hy;
  const double across = along_x ? (y - cy) : (x - cx);
  const double facing = along_x ? sun_v_ : sun_u_;
  const double side = smoothstep(-0.5 * ew_, 0.5 * ew_, across) * 2 - 1;  // -1 .. 1 across the ridge
  const double lit = roof * (1 + 0.25 * side * (facing > 0 ? 1 : -1));
  const double sd_roof = rect_sd(x, y, cx, cy, hx, hy);
  // Roof edge: a thin bright parapet (0.6 m).
  const double rim = 1 - inside(sd_roof - 0.6, ew_);
  const double roof_a = lerp(lit, 0.75, 0.6 * rim);
  return lerp(a, roof_a, inside(sd_roof, ew_));
}

[[gnu::always_inline]] inline double SynthTexture::woodland(double u, double v) const {
  AlbedoMemo& mm = memo();
  const double x = u * inv_crown_, y = v * inv_crown_;
  const double c = value_noise(noise_seed_[1], x, y, mm.crown[0]) + 0.5 * value_noise(noise_seed_[2], 2 * x, 2 * y, mm.crown[1]);
  const double crown = smoothstep(-0.3, 0.5, c);
  return 0.07 + 0.2 * crown;
}

namespace {
// The albedo from its layout a: large-scale modulation and fine ground noise (wavelength >= 2 gsd), clamped.
// large, fine: the seeds of their noises; inv_fine: 1 / the fine noise's wavelength.
inline double modulate(double a, double X, double Y, uint64_t large, uint64_t fine, double inv_fine, AlbedoMemo& mm) {
  a *= 1 + 0.15 * value_noise(large, X * (1.0 / 180), Y * (1.0 / 180), mm.large);
  a += 0.025 * value_noise(fine, X * inv_fine, Y * inv_fine, mm.fine);
  return std::clamp(a, 0.02, 0.98);
}
}  // namespace

// Inline, as are farmland, urban and woodland in it: albedo_n runs it a point at a time, and the calls
// (arguments, saved registers, a large frame) were ~8 % of the texture's instructions.
[[gnu::always_inline]] inline double SynthTexture::layout(double X, double Y) const {
  const double u = ca_ * X + sa_ * Y + ou_, v = -sa_ * X + ca_ * Y + ov_;
  const int64_t bi = synth::floor_int(u * inv_block_), bj = synth::floor_int(v * inv_block_);
  const double lu = u - bi * block_, lv = v - bj * block_;
  AlbedoMemo& mm = memo();
  const BlockLines& bl = kept(mm.block, seed_, bi, bj, 0, [&] {
    BlockLines c;
    c.type = hash(seed_, 1, bi, bj);
    for (int e = 0; e < 2; ++e) {
      c.road[0][e] = draw_road(seed_, 0, bi + e);
      c.road[1][e] = draw_road(seed_, 1, bj + e);
    }
    return c;
  });
  const double type = synth::unit(bl.type);
  double a;
  if (type < 0.55)
    a = farmland(bi, bj, lu, lv, u, v);
  else if (type < 0.82)
    a = urban(bi, bj, lu, lv, u, v);
  else
    a = woodland(u, v);
  // Every block fades to a common verge albedo at its border (2 m), so the albedo is continuous there.
  const double db = std::min(std::min(lu, block_ - lu), std::min(lv, block_ - lv));
  a = lerp(0.3, a, inside(db - 2.0, ew_));
  // Roads on some whole block-grid lines (u = i B or v = j B), 6..12 m wide, with dashed centre lines.
  for (int axis = 0; axis < 2; ++axis) {
    const double l = axis == 0 ? lu : lv;
    const double dist = std::min(l, block_ - l);
    const Road& rd = bl.road[axis][l > block_ / 2 ? 1 : 0];  // line (axis == 0 ? bi : bj) + 0 or 1
    if (!rd.present) continue;
    const double half = rd.half;
    if (dist > half + ew_) continue;
    double r = rd.asphalt + 0.03 * value_noise(rd.noise_seed, u / 2, v / 2, mm.asphalt);
    // Dashed centre marking: 0.4 m wide (at least one edge width), 3 m dashes every 9 m.
    const double along = axis == 0 ? v : u;
    const double n9 = along * (1.0 / 9), phase = n9 - static_cast<double>(synth::floor_int(n9));
    const double dash = inside(1.5 / 9 - std::abs(phase - 0.5), ew_ / 9);
    r = lerp(r, 0.85, dash * inside(0.2 - dist, ew_) * (half > 4 ? 1 : 0));
    a = lerp(a, r, inside(half - dist, ew_));
  }
  return a;
}

double SynthTexture::albedo(double X, double Y) const {
  return modulate(layout(X, Y), X, Y, noise_seed_[3], noise_seed_[4], inv_fine_, memo());
}

TPKIT_HOT void SynthTexture::albedo_n(long n, const double* X, const double* Y, double* out) const {
  for (long i = 0; i < n; ++i) out[i] = layout(X[i], Y[i]);
  AlbedoMemo& mm = memo();
  for (long i = 0; i < n; ++i) out[i] = modulate(out[i], X[i], Y[i], noise_seed_[3], noise_seed_[4], inv_fine_, mm);
}

}  // namespace tpkit
