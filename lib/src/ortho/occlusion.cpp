#include "tpkit/ortho/occlusion.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace tpkit {

LineOfSight line_of_sight(const RpcModel& model, const OrthoGrid& g, const GridCrs& crs, double c, double r, double h) {
  // three ground points: (c, r), one pixel right, one pixel down
  double x[3] = {g.x0 + (c + 0.5) * g.gsd, g.x0 + (c + 1.5) * g.gsd, g.x0 + (c + 0.5) * g.gsd};
  double y[3] = {g.y0 - (r + 0.5) * g.gsd, g.y0 - (r + 0.5) * g.gsd, g.y0 - (r + 1.5) * g.gsd};
  crs.to_lonlat(3, x, y);
  const Eigen::Vector2d p0 = model.project(x[0], y[0], h);
  const Eigen::Vector2d pc = model.project(x[1], y[1], h) - p0, pr = model.project(x[2], y[2], h) - p0;
  const Eigen::Vector2d ph = model.project(x[0], y[0], h + 1) - p0;
  // the image point stays where it is: pc dc + pr dr + ph = 0
  Eigen::Matrix2d A;
  A << pc, pr;
  LineOfSight los{NAN, NAN};
  if (!(std::abs(A.determinant()) > 1e-12) || !ph.allFinite()) return los;
  const Eigen::Vector2d d = A.partialPivLu().solve(-ph);
  los.dc = d.x();
  los.dr = d.y();
  return los;
}

long occluder_margin(const LineOfSight& los, double relief_m, long cap) {
  const double per_m = std::hypot(los.dc, los.dr);
  if (!std::isfinite(per_m) || !std::isfinite(relief_m)) return 0;
  return std::min(cap, static_cast<long>(std::ceil(std::max(0.0, relief_m) * per_m)) + 2);
}

long mark_walls(const HeightWindow& H, double gsd, double slope_deg, long c0, long r0, long w, long h, std::vector<char>& hidden) {
  hidden.resize(static_cast<size_t>(w * h), 0);
  const double limit = std::tan(slope_deg * M_PI / 180) * 2 * gsd;  // metres over two pixels
  auto z = [&](long c, long r) { return H.z[static_cast<size_t>((r - H.r0) * H.width + (c - H.c0))]; };
  long n = 0;
  for (long r = std::max(r0, H.r0 + 1); r < std::min(r0 + h, H.r0 + H.height - 1); ++r)
    for (long c = std::max(c0, H.c0 + 1); c < std::min(c0 + w, H.c0 + H.width - 1); ++c) {
      char& m = hidden[static_cast<size_t>((r - r0) * w + (c - c0))];
      if (m) continue;
      const double gx = z(c + 1, r) - z(c - 1, r), gy = z(c, r + 1) - z(c, r - 1);
      if (std::hypot(gx, gy) > limit) m = 1, ++n;  // (NaN: not a wall)
    }
  return n;
}

long mark_hidden(const HeightWindow& H, const LineOfSight& los, long c0, long r0, long w, long h, double tolerance,
                 std::vector<char>& hidden) {
  hidden.assign(static_cast<size_t>(w * h), 0);
  const double per_m = std::hypot(los.dc, los.dr);
  if (!std::isfinite(per_m) || per_m < 1e-9) return 0;  // a vertical view hides nothing
  double top = -INFINITY;
  for (double z : H.z)
    if (std::isfinite(z)) top = std::max(top, z);
  // unit steps of half a pixel along the line of sight; the ray rises rise_m per step
  const double step = 0.5, ux = los.dc / per_m * step, uy = los.dr / per_m * step, rise = step / per_m;
  auto at = [&](long c, long r) { return H.z[static_cast<size_t>((r - H.r0) * H.width + (c - H.c0))]; };
  // the window's surface at grid position (c, r), bilinear; NaN outside or where a sample is unknown
  auto surface = [&](double c, double r) {
    const double fc = c - H.c0, fr = r - H.r0;
    if (!(fc >= 0 && fr >= 0 && fc <= H.width - 1 && fr <= H.height - 1)) return double(NAN);
    const long i = std::min(static_cast<long>(fc), H.width - 2), j = std::min(static_cast<long>(fr), H.height - 2);
    const double u = fc - i, v = fr - j;
    const double* z = &H.z[static_cast<size_t>(j * H.width + i)];
    return (1 - v) * ((1 - u) * z[0] + u * z[1]) + v * ((1 - u) * z[H.width] + u * z[H.width + 1]);
  };
  long n = 0;
  for (long r = r0; r < r0 + h; ++r)
    for (long c = c0; c < c0 + w; ++c) {
      const double z0 = at(c, r);
      if (!std::isfinite(z0)) continue;
      const long steps = static_cast<long>(std::ceil((top - z0) / rise));
      for (long s = 2; s <= steps; ++s) {  // from one pixel on: the pixel's own slope is not an occluder
        const double zs = surface(c + s * ux, r + s * uy);
        if (std::isnan(zs)) {
          if (!(c + s * ux >= H.c0 && r + s * uy >= H.r0 && c + s * ux <= H.c0 + H.width - 1 && r + s * uy <= H.r0 + H.height - 1)) break;
          continue;
        }
        if (zs > z0 + s * rise + tolerance) {
          hidden[static_cast<size_t>((r - r0) * w + (c - c0))] = 1;
          ++n;
          break;
        }
      }
    }
  return n;
}

}  // namespace tpkit
