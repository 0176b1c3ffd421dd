#include "tpkit/match/window_size.hpp"

#include <algorithm>
#include <limits>

#include "tpkit/core/text_table.hpp"
#include "tpkit/match/radiometric_highpass.hpp"

namespace tpkit {

double robust_spread(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  auto median = [](std::vector<double>& x) {
    const auto mid = x.begin() + static_cast<std::ptrdiff_t>(x.size() / 2);
    std::nth_element(x.begin(), mid, x.end());
    return *mid;
  };
  const double m = median(v);
  for (double& x : v) x = std::abs(x - m);
  return 1.4826 * median(v);
}

double along_across_ratio(const std::vector<Eigen::Vector2d>& d, const Eigen::Vector2d& dir) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (d.size() < 8 || !(dir.norm() > 0)) return nan;
  const Eigen::Vector2d e = dir.normalized(), n(-e.y(), e.x());
  std::vector<double> along, across;
  for (const Eigen::Vector2d& v : d) along.push_back(v.dot(e)), across.push_back(v.dot(n));
  const double a = robust_spread(std::move(along)), c = robust_spread(std::move(across));
  return c > 0 ? a / c : nan;
}

WindowSizeChoice choose_window_size(const std::function<WindowSizeSample(const WindowSize&)>& refine, const WindowSize& base,
                                    const std::vector<WindowSize>& candidates, const Eigen::Vector2d& epipolar_dir, double max_ratio,
                                    double min_gain) {
  WindowSizeChoice c;
  c.size = base;
  if (candidates.empty()) return c;
  const WindowSizeSample at_base = refine(base);
  WindowSizeSample before = at_base;
  bool size_kept = false;  // a candidate of the current size was kept
  for (size_t i = 0; i < candidates.size(); ++i) {
    const WindowSize& w = candidates[i];
    if (i > 0 && !w.same_size(candidates[i - 1])) {
      if (!size_kept) break;  // no model of the last size was kept: larger ones are not tried
      size_kept = false;
    } else if (size_kept) {
      continue;  // this size has its model
    }
    const WindowSizeSample s = refine(w);
    WindowSizeChoice::Tried t;
    t.size = w;
    std::vector<Eigen::Index> common;
    for (Eigen::Index k = 0; k < s.xy.rows(); ++k)
      if (at_base.ok[static_cast<size_t>(k)] && before.ok[static_cast<size_t>(k)] && s.ok[static_cast<size_t>(k)]) common.push_back(k);
    t.common = static_cast<long>(common.size());
    std::vector<Eigen::Vector2d> d;
    Eigen::MatrixX4d xb(t.common, 4), xs(t.common, 4);
    for (size_t q = 0; q < common.size(); ++q) {
      const Eigen::Index k = common[q];
      d.push_back(s.xy.row(k).tail<2>().transpose() - at_base.xy.row(k).tail<2>().transpose());
      xb.row(static_cast<Eigen::Index>(q)) = before.xy.row(k);
      xs.row(static_cast<Eigen::Index>(q)) = s.xy.row(k);
    }
    t.ratio = along_across_ratio(d, epipolar_dir);
    t.spread_before = epipolar_spread(xb);
    t.spread = epipolar_spread(xs);
    t.kept = t.ratio <= max_ratio && t.spread <= (1 - min_gain) * t.spread_before;  // false on NaN
    c.tried.push_back(t);
    if (!t.kept) continue;
    size_kept = true;
    c.size = w;
    before = s;
  }
  return c;
}

std::vector<WindowSize> window_size_candidates() { return {{5, 29, false}, {5, 29, true}, {7, 39, false}, {7, 39, true}}; }

std::string describe_window_size(const WindowSizeChoice& c, bool given, const std::string& not_estimated, const std::string& sampled,
                                 double max_ratio, double min_gain) {
  auto px = [](double v) { return std::isfinite(v) ? format_number(std::round(v * 1e4) / 1e4) : std::string("undefined"); };
  auto model = [&c](const WindowSize& w) { return !c.shapes ? std::string() : w.quadratic ? std::string(" quadratic") : std::string(" affine"); };
  std::string s = "taper " + format_number(c.size.taper) + " px, window " + std::to_string(c.size.window) + " px" +
                  (c.shapes ? "," + model(c.size) : std::string());
  if (given) return s + " (--window/--taper)";
  if (c.tried.empty()) return s + " " + not_estimated;
  s += " (estimated on " + std::to_string(c.samples) + " " + sampled + ";";
  for (const WindowSizeChoice::Tried& t : c.tried)
    s += " taper " + format_number(t.size.taper) + " px" + model(t.size) + ": differences along / across the epipolar lines " +
         (std::isfinite(t.ratio) ? format_number(std::round(t.ratio * 100) / 100) : std::string("undefined")) + ", spread " +
         px(t.spread_before) + " -> " + px(t.spread) + " px over " + std::to_string(t.common) + (t.kept ? ", kept;" : ", refused;");
  s.pop_back();
  return s + "; a larger window is kept where the ratio is at most " + format_number(max_ratio) + " and the spread falls by " +
         format_number(min_gain * 100) + "%)";
}

}  // namespace tpkit
