#include "tpkit/rpc/epipolar_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tpkit/core/parallel_for.hpp"

namespace tpkit {

namespace {
// The exact curve point, or NaN where the localization fails (a node that poisons its cells).
Eigen::Vector2d exact_point(const RpcModel& a, const RpcModel& b, double x, double y, double h) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return epipolar_point(a, b, x, y, h).value_or(Eigen::Vector2d(nan, nan));
}
}  // namespace

EpipolarGrid::EpipolarGrid(const RpcModel& a, const RpcModel& b, double x0, double y0, double x1, double y1, double h_lo,
                           double h_hi, const EpipolarGridOptions& o, int threads)
    : x0_(x0), y0_(y0), x1_(x1), y1_(y1), h_lo_(h_lo), h_hi_(h_hi) {
  if (!(x1 >= x0) || !(y1 >= y0) || !(h_hi > h_lo) || !(o.spacing > 0) || o.levels < 2) return;
  double step = o.spacing;
  int levels = o.levels;
  for (int round = 0; round <= std::max(0, o.refinements); ++round, step /= 2, levels = 2 * levels - 1) {
    const double nodes = (std::ceil((x1 - x0) / step) + 1) * (std::ceil((y1 - y0) / step) + 1) * levels;
    if (o.max_nodes > 0 && nodes > static_cast<double>(o.max_nodes)) break;
    if (build(a, b, step, levels, o.tolerance, threads)) return;
  }
  ok_ = false;
  q_.clear();  // not trusted: point() refuses
}

bool EpipolarGrid::build(const RpcModel& a, const RpcModel& b, double step, int levels, double tolerance, int threads) {
  ok_ = false;
  step_ = step;
  nx_ = std::max(2, static_cast<int>(std::ceil((x1_ - x0_) / step)) + 1);
  ny_ = std::max(2, static_cast<int>(std::ceil((y1_ - y0_) / step)) + 1);
  nh_ = levels;
  dh_ = (h_hi_ - h_lo_) / (nh_ - 1);
  q_.assign(static_cast<size_t>(nx_) * ny_ * nh_, Eigen::Vector2d::Zero());
  // the nodes, one row (j, k) a task
  parallel_for(static_cast<size_t>(ny_) * nh_, threads, [&](size_t row) {
    const int j = static_cast<int>(row % ny_), k = static_cast<int>(row / ny_);
    const double y = y0_ + j * step_, h = h_lo_ + k * dh_;
    for (int i = 0; i < nx_; ++i) q_[row * nx_ + i] = exact_point(a, b, x0_ + i * step_, y, h);
  });
  ok_ = true;  // for point() in the check
  // the check: every cell's centre, midway between two levels (the pair turning from cell to cell)
  const int cells_x = nx_ - 1, cells_y = ny_ - 1;
  std::vector<double> err(static_cast<size_t>(cells_y), 0.0);
  parallel_for(static_cast<size_t>(cells_y), threads, [&](size_t jc) {
    const int j = static_cast<int>(jc);
    for (int i = 0; i < cells_x; ++i) {
      const double x = std::min(x1_, x0_ + (i + 0.5) * step_), y = std::min(y1_, y0_ + (j + 0.5) * step_);
      const double h = h_lo_ + ((i + j) % (nh_ - 1) + 0.5) * dh_;
      Eigen::Vector2d g;
      const Eigen::Vector2d e = exact_point(a, b, x, y, h);
      if (!e.allFinite() || !point(x, y, h, g)) continue;  // failed nodes: those cells are refused anyway
      err[jc] = std::max(err[jc], (g - e).norm());
    }
  });
  check_error_ = *std::max_element(err.begin(), err.end());
  ok_ = check_error_ <= tolerance;
  return ok_;
}

bool EpipolarGrid::point(double x, double y, double h, Eigen::Vector2d& q) const {
  if (!ok_ || !(x >= x0_ && x <= x1_ && y >= y0_ && y <= y1_ && h >= h_lo_ && h <= h_hi_)) return false;
  // cell (i, j, k) and the position within it, each in [0, 1]
  auto locate = [](double v, double step, int n, int& c) {
    const double f = v / step;
    c = std::min(static_cast<int>(f), n - 2);
    return f - c;
  };
  int i, j, k;
  const double tx = locate(x - x0_, step_, nx_, i), ty = locate(y - y0_, step_, ny_, j), tz = locate(h - h_lo_, dh_, nh_, k);
  Eigen::Vector2d s = Eigen::Vector2d::Zero();
  for (int dk = 0; dk < 2; ++dk)
    for (int dj = 0; dj < 2; ++dj) {
      const Eigen::Vector2d* n = &q_[(static_cast<size_t>(k + dk) * ny_ + (j + dj)) * nx_ + i];
      const double w = (dk ? tz : 1 - tz) * (dj ? ty : 1 - ty);
      s += w * ((1 - tx) * n[0] + tx * n[1]);
    }
  if (!s.allFinite()) return false;  // a failed node among the eight
  q = s;
  return true;
}

}  // namespace tpkit
