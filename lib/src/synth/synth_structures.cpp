// Buildings and trees of a tp-synth scene (synth_structures.hpp).
#include "tpkit/synth/synth_structures.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "tpkit/core/error.hpp"
#include "tpkit/synth/synth_noise.hpp"
#include "tpkit/synth/synth_terrain.hpp"

namespace tpkit {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

SynthStructures::SynthStructures(uint64_t seed, double buildings, double trees, double x0, double y0, double x1,
                                 double y1, const SynthTerrain& terrain) {
  if (!(buildings >= 0 && buildings <= 1 && trees >= 0 && trees <= 1)) throw NumericalError("synth structures: bad density");
  if (buildings == 0 && trees == 0) return;
  const uint64_t s = synth::hash(seed, 0xb111d);
  auto u = [&](int64_t a, int64_t b = 0, int64_t c = 0) { return synth::uniform(s, a, b, c); };
  // The lot grid: rotated by 10..35 deg from the image axes (walls are oblique in every view), seeded offset.
  const double ang = (10 + 25 * u(1)) * kPi / 180;
  ca_ = std::cos(ang);
  sa_ = std::sin(ang);
  ox_ = kLot * u(2);
  oy_ = kLot * u(3);
  double ulo = kInf, uhi = -kInf, vlo = kInf, vhi = -kInf;
  for (double X : {x0, x1})
    for (double Y : {y0, y1}) {
      const Eigen::Vector3d q = to_lot({X, Y, 0});
      ulo = std::min(ulo, q.x()), uhi = std::max(uhi, q.x()), vlo = std::min(vlo, q.y()), vhi = std::max(vhi, q.y());
    }
  i0_ = static_cast<long>(std::floor(ulo / kLot));
  j0_ = static_cast<long>(std::floor(vlo / kLot));
  ni_ = static_cast<long>(std::floor(uhi / kLot)) - i0_ + 1;
  nj_ = static_cast<long>(std::floor(vhi / kLot)) - j0_ + 1;
  lots_.assign(static_cast<size_t>(ni_ * nj_), Lot{});
  auto ground = [&](double lu, double lv) {  // terrain height under lot-frame (u, v)
    const double X = ox_ + ca_ * lu - sa_ * lv, Y = oy_ + sa_ * lu + ca_ * lv;
    return terrain.height(X, Y);
  };
  zbase_ = terrain.zmin() - 1;
  for (long j = 0; j < nj_; ++j)
    for (long i = 0; i < ni_; ++i) {
      Lot& lot = lots_[static_cast<size_t>(j * ni_ + i)];
      const int64_t gi = i0_ + i, gj = j0_ + j;
      const double lu0 = gi * kLot, lv0 = gj * kLot;
      if (u(10, gi, gj) < buildings) {
        // Footprint: each side 45..85 % of the lot less its 2 m streets, anywhere inside them.
        const double inner = kLot - 4;
        const double w = inner * (0.45 + 0.4 * u(11, gi, gj)), h = inner * (0.45 + 0.4 * u(12, gi, gj));
        Building b;
        b.u0 = lu0 + 2 + (inner - w) * u(13, gi, gj);
        b.v0 = lv0 + 2 + (inner - h) * u(14, gi, gj);
        b.u1 = b.u0 + w;
        b.v1 = b.v0 + h;
        // Roof above the highest terrain under the footprint (sampled every metre: the terrain varies on
        // the scale of its 4 gsd control spacing; a peak poking through a roof would still be exact truth).
        double zg = -kInf;
        const int nu = 1 + static_cast<int>(std::ceil(w)), nv = 1 + static_cast<int>(std::ceil(h));
        for (int b2 = 0; b2 <= nv; ++b2)
          for (int a2 = 0; a2 <= nu; ++a2) zg = std::max(zg, ground(b.u0 + w * a2 / nu, b.v0 + h * b2 / nv));
        const double r = u(15, gi, gj);
        b.zr = zg + 6 + 30 * r * std::sqrt(r);
        b.roof = 0.25 + 0.5 * u(16, gi, gj);
        b.wall = 0.3 + 0.45 * u(17, gi, gj);
        b.seed = synth::hash(s, 18, gi, gj);
        lot.building = static_cast<int>(buildings_.size());
        buildings_.push_back(b);
        zmax_ = std::max(zmax_, b.zr);
      } else if (u(20, gi, gj) < trees) {
        // 1..4 trees anywhere in the lot, each a crown of a main lobe and 2..3 smaller ones around it.
        const int nt = 1 + static_cast<int>(4 * u(21, gi, gj)) % 4;
        lot.lobe0 = static_cast<int>(lobes_.size());
        for (int t = 0; t < nt; ++t) {
          const double rh = 2 + 2.5 * u(22, gi, gj * 8 + t);
          const double reach = rh * 1.6 + 0.5;  // lobes below stay within this radius of the centre
          const double cu = lu0 + reach + (kLot - 2 * reach) * u(23, gi, gj * 8 + t);
          const double cv = lv0 + reach + (kLot - 2 * reach) * u(24, gi, gj * 8 + t);
          const double trunk = 2 + 3 * u(25, gi, gj * 8 + t);
          const double rz = rh * (0.8 + 0.3 * u(26, gi, gj * 8 + t));
          const double zc = ground(cu, cv) + trunk + rz;
          lobes_.push_back({cu, cv, zc, rh, rz, synth::hash(s, 27, gi, gj * 8 + t)});
          const int nl = 2 + static_cast<int>(2 * u(28, gi, gj * 8 + t)) % 2;
          for (int l = 0; l < nl; ++l) {
            const double a = 2 * kPi * (u(29, gi, (gj * 8 + t) * 4 + l) + l / static_cast<double>(nl));
            const double rr = rh * (0.55 + 0.2 * u(30, gi, (gj * 8 + t) * 4 + l));
            const double off = rh * (0.5 + 0.3 * u(31, gi, (gj * 8 + t) * 4 + l));  // off + rr <= 1.6 rh
            lobes_.push_back({cu + off * std::cos(a), cv + off * std::sin(a),
                              zc + rh * (-0.25 + 0.35 * u(32, gi, (gj * 8 + t) * 4 + l)), rr, rr * rz / rh,
                              synth::hash(s, 33, gi, (gj * 8 + t) * 4 + l)});
          }
          ++trees_;
        }
        lot.lobe1 = static_cast<int>(lobes_.size());
        for (int k = lot.lobe0; k < lot.lobe1; ++k) zmax_ = std::max(zmax_, lobes_[k].cz + lobes_[k].rz);
      }
    }
  if (empty()) zmax_ = -kInf;
}

Eigen::Vector3d SynthStructures::to_lot(const Eigen::Vector3d& X) const {
  const double dx = X.x() - ox_, dy = X.y() - oy_;
  return {ca_ * dx + sa_ * dy, -sa_ * dx + ca_ * dy, X.z()};
}
Eigen::Vector3d SynthStructures::dir_to_lot(const Eigen::Vector3d& d) const {
  return {ca_ * d.x() + sa_ * d.y(), -sa_ * d.x() + ca_ * d.y(), d.z()};
}
Eigen::Vector3d SynthStructures::dir_to_ground(const Eigen::Vector3d& d) const {
  return {ca_ * d.x() - sa_ * d.y(), sa_ * d.x() + ca_ * d.y(), d.z()};
}

// The objects of one lot against o + t d (lot frame), t in [tmin, tmax]: the nearest entering hit.
bool SynthStructures::lot_hit(const Lot& lot, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmin, double tmax,
                              SynthStructureHit* hit) const {
  bool found = false;
  double best = tmax;
  if (lot.building >= 0) {
    // Slabs: the entering parameter is the largest of the three near sides; its axis gives the normal.
    const Building& b = buildings_[static_cast<size_t>(lot.building)];
    const double lo[3] = {b.u0, b.v0, zbase_}, hi[3] = {b.u1, b.v1, b.zr};
    double tn = -kInf, tf = kInf;
    int axis = -1;
    bool miss = false;
    for (int a = 0; a < 3 && !miss; ++a) {
      if (d[a] == 0) {
        miss = o[a] < lo[a] || o[a] > hi[a];
        continue;
      }
      double t1 = (lo[a] - o[a]) / d[a], t2 = (hi[a] - o[a]) / d[a];
      if (t1 > t2) std::swap(t1, t2);
      if (t1 > tn) tn = t1, axis = a;
      tf = std::min(tf, t2);
    }
    if (!miss && axis >= 0 && tn <= tf && tn >= tmin && tn <= best) {
      best = tn;
      found = true;
      if (hit) {
        Eigen::Vector3d n = Eigen::Vector3d::Zero();
        n[axis] = d[axis] > 0 ? -1 : 1;
        hit->t = tn;
        hit->normal = n;
        hit->kind = axis == 2 ? kRoof : kWall;
        hit->id = lot.building;
      }
    }
  }
  for (int k = lot.lobe0; k < lot.lobe1; ++k) {
    // Ellipsoid lobe: scaled to the unit sphere, |q0 + t qd|^2 = 1; the smaller root enters.
    const Lobe& L = lobes_[static_cast<size_t>(k)];
    const Eigen::Vector3d q0((o.x() - L.cu) / L.rh, (o.y() - L.cv) / L.rh, (o.z() - L.cz) / L.rz);
    const Eigen::Vector3d qd(d.x() / L.rh, d.y() / L.rh, d.z() / L.rz);
    const double A = qd.squaredNorm(), B = q0.dot(qd), C = q0.squaredNorm() - 1;
    const double disc = B * B - A * C;
    if (!(disc > 0)) continue;
    // the entering root, without cancellation
    const double sq = std::sqrt(disc);
    const double t = B > 0 ? C / (-B - sq) : (-B - sq) / A;
    if (!(t >= tmin && t <= best)) continue;
    best = t;
    found = true;
    if (hit) {
      const Eigen::Vector3d p = o + t * d;
      hit->t = t;
      hit->normal = Eigen::Vector3d((p.x() - L.cu) / (L.rh * L.rh), (p.y() - L.cv) / (L.rh * L.rh), (p.z() - L.cz) / (L.rz * L.rz)).normalized();
      hit->kind = kTree;
      hit->id = k;
    }
  }
  return found;
}

bool SynthStructures::intersect(const Eigen::Vector3d& og, const Eigen::Vector3d& dg, double tmin, double tmax,
                                SynthStructureHit* hit) const {
  if (empty()) return false;
  const Eigen::Vector3d o = to_lot(og), d = dir_to_lot(dg);
  // The part of the ray inside the slab of heights [zbase, zmax] and the lot grid's rectangle.
  double ta = tmin, tb = tmax;
  auto clip = [&](double p, double dp, double lo, double hi) {
    if (dp == 0) {
      if (p < lo || p > hi) tb = -kInf;
      return;
    }
    double t1 = (lo - p) / dp, t2 = (hi - p) / dp;
    if (t1 > t2) std::swap(t1, t2);
    ta = std::max(ta, t1);
    tb = std::min(tb, t2);
  };
  clip(o.z(), d.z(), zbase_, zmax_);
  clip(o.x(), d.x(), i0_ * kLot, (i0_ + ni_) * kLot);
  clip(o.y(), d.y(), j0_ * kLot, (j0_ + nj_) * kLot);
  if (!(ta <= tb)) return false;
  // 2-D traversal of the lots from ta to tb.
  const double ua = o.x() + ta * d.x(), va = o.y() + ta * d.y();
  long i = std::clamp(static_cast<long>(std::floor(ua / kLot)), i0_, i0_ + ni_ - 1);
  long j = std::clamp(static_cast<long>(std::floor(va / kLot)), j0_, j0_ + nj_ - 1);
  const int si = d.x() > 0 ? 1 : -1, sj = d.y() > 0 ? 1 : -1;
  double tnu = d.x() != 0 ? ((d.x() > 0 ? (i + 1) * kLot : i * kLot) - o.x()) / d.x() : kInf;
  double tnv = d.y() != 0 ? ((d.y() > 0 ? (j + 1) * kLot : j * kLot) - o.y()) / d.y() : kInf;
  const double tdu = d.x() != 0 ? kLot / std::abs(d.x()) : kInf, tdv = d.y() != 0 ? kLot / std::abs(d.y()) : kInf;
  SynthStructureHit h;
  while (true) {
    if (i < i0_ || i >= i0_ + ni_ || j < j0_ || j >= j0_ + nj_) return false;
    const Lot& lot = lots_[static_cast<size_t>((j - j0_) * ni_ + (i - i0_))];
    // every object lies inside its lot: a hit here comes before any hit in a later lot
    if ((lot.building >= 0 || lot.lobe1 > lot.lobe0) && lot_hit(lot, o, d, tmin, tmax, hit ? &h : nullptr)) {
      if (hit) {
        *hit = h;
        hit->normal = dir_to_ground(h.normal);
      }
      return true;
    }
    const double texit = std::min(tnu, tnv);
    if (texit >= tb) return false;
    if (tnu < tnv) {
      i += si;
      tnu += tdu;
    } else {
      j += sj;
      tnv += tdv;
    }
  }
}

double SynthStructures::top(double X, double Y, Eigen::Vector2d* grad) const {
  if (grad) grad->setZero();
  if (empty()) return -kInf;
  const Eigen::Vector3d q = to_lot({X, Y, 0});
  const long i = static_cast<long>(std::floor(q.x() / kLot)), j = static_cast<long>(std::floor(q.y() / kLot));
  if (i < i0_ || i >= i0_ + ni_ || j < j0_ || j >= j0_ + nj_) return -kInf;
  const Lot& lot = lots_[static_cast<size_t>((j - j0_) * ni_ + (i - i0_))];
  double z = -kInf;
  Eigen::Vector2d g = Eigen::Vector2d::Zero();  // lot frame
  if (lot.building >= 0) {
    const Building& b = buildings_[static_cast<size_t>(lot.building)];
    if (q.x() >= b.u0 && q.x() <= b.u1 && q.y() >= b.v0 && q.y() <= b.v1) z = b.zr;
  }
  for (int k = lot.lobe0; k < lot.lobe1; ++k) {
    const Lobe& L = lobes_[static_cast<size_t>(k)];
    const double a = (q.x() - L.cu) / L.rh, b = (q.y() - L.cv) / L.rh, r2 = a * a + b * b;
    if (r2 >= 1) continue;
    const double w = std::sqrt(1 - r2), zk = L.cz + L.rz * w;
    if (zk > z) {
      z = zk;
      g = Eigen::Vector2d(-L.rz * a / (L.rh * w), -L.rz * b / (L.rh * w));
    }
  }
  if (grad && std::isfinite(z)) *grad = Eigen::Vector2d(ca_ * g.x() - sa_ * g.y(), sa_ * g.x() + ca_ * g.y());
  return z;
}

double SynthStructures::albedo(int kind, int id, const Eigen::Vector3d& X, double gsd) const {
  const double ew = std::max(gsd, 0.3);  // edge width (m)
  const double fine = std::max(1.0, 2 * gsd);
  double a = 0.5;
  if (kind == kRoof || kind == kWall) {
    const Building& b = buildings_.at(static_cast<size_t>(id));
    const Eigen::Vector3d q = to_lot(X);
    if (kind == kRoof) {
      // a grey with a weathered texture, and a few darker fixtures (vents, skylights) on a 6 m grid
      const double n = synth::value_noise(b.seed, q.x() / (1.5 * fine), q.y() / (1.5 * fine));
      const double fu = std::fmod(q.x() - b.u0 + 600, 6.0), fv = std::fmod(q.y() - b.v0 + 600, 6.0);
      const double fix = synth::smoothstep(1.5, 1.5 + ew, fu) * (1 - synth::smoothstep(3.5, 3.5 + ew, fu)) *
                         synth::smoothstep(2.0, 2.0 + ew, fv) * (1 - synth::smoothstep(3.5, 3.5 + ew, fv));
      const bool fixtures = (b.seed & 3) != 0;
      a = b.roof * (1 + 0.2 * n) * (fixtures ? 1 - 0.45 * fix : 1.0);
    } else {
      // windows: rows every 3 m down from the roof, columns every 2.5 m along the wall
      const bool along_u = std::abs(q.y() - b.v0) < 1e-6 * (1 + std::abs(b.v0)) || std::abs(q.y() - b.v1) < 1e-6 * (1 + std::abs(b.v1));
      const double s = along_u ? q.x() - b.u0 : q.y() - b.v0;
      const double fz = std::fmod(b.zr - X.z(), 3.0), fs = std::fmod(s + 600, 2.5);
      const double win = synth::smoothstep(0.8, 0.8 + ew, fz) * (1 - synth::smoothstep(2.2, 2.2 + ew, fz)) *
                         synth::smoothstep(0.6, 0.6 + ew, fs) * (1 - synth::smoothstep(1.9, 1.9 + ew, fs));
      const double n = synth::value_noise(b.seed ^ 0x3a11, s / (2 * fine), X.z() / (2 * fine));
      a = b.wall * (1 + 0.1 * n) * (1 - 0.55 * win);
    }
  } else if (kind == kTree) {
    const Lobe& L = lobes_.at(static_cast<size_t>(id));
    const double n1 = synth::value_noise(L.seed, X.x() / fine, X.y() / fine);
    const double n2 = synth::value_noise(L.seed ^ 0x7ee, X.x() / (2.5 * fine), (X.y() + X.z()) / (2.5 * fine));
    a = 0.13 * (1 + 0.35 * n1 + 0.25 * n2);
  }
  return std::clamp(a, 0.02, 0.98);
}

}  // namespace tpkit
