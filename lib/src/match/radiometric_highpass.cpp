#include "tpkit/match/radiometric_highpass.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tpkit/core/text_table.hpp"
#include "tpkit/match/affine_fundamental.hpp"
#include "tpkit/match/relative_blur.hpp"

namespace tpkit {

void highpass_raster(Raster& r, double sigma) {
  if (!(sigma > 0) || r.data.empty()) return;
  Raster mean = r;
  blur_raster(mean, sigma);
  for (size_t k = 0; k < r.data.size(); ++k) r.data[k] -= mean.data[k];  // NaN stays NaN
}

namespace {
double median_of(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}
}  // namespace

double epipolar_spread(const Eigen::MatrixX4d& xy) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (xy.rows() < 8) return nan;
  AffineFundamental F;
  if (!fit_affine_fundamental(xy, {}, F)) return nan;
  auto distances = [&](const AffineFundamental& f) {
    std::vector<double> d(static_cast<size_t>(xy.rows()));
    for (Eigen::Index k = 0; k < xy.rows(); ++k) d[static_cast<size_t>(k)] = std::abs(f.residual(xy(k, 0), xy(k, 1), xy(k, 2), xy(k, 3)));
    return d;
  };
  // one refit without the gross outliers (a verified match may still be a few tenths of a pixel off)
  const std::vector<double> d = distances(F);
  const double cut = 5 * median_of(d);
  std::vector<int> keep;
  for (size_t k = 0; k < d.size(); ++k)
    if (d[k] <= cut) keep.push_back(static_cast<int>(k));
  if (keep.size() >= 8 && keep.size() < d.size()) {
    AffineFundamental G;
    if (fit_affine_fundamental(xy, keep, G)) F = G;
  }
  if (!(std::hypot(F.n(0), F.n(1)) > 1e-6)) return nan;  // no epipolar direction in image 2
  std::vector<double> e(static_cast<size_t>(xy.rows()));
  for (Eigen::Index k = 0; k < xy.rows(); ++k) e[static_cast<size_t>(k)] = F.epipolar_distance2(xy(k, 0), xy(k, 1), xy(k, 2), xy(k, 3));
  return median_of(e);
}

HighpassChoice choose_highpass(const std::function<double(double)>& spread, const std::vector<double>& candidates, double min_gain,
                               double next_gain) {
  HighpassChoice c;
  c.spread_none = spread(0.0);
  c.spread = c.spread_none;
  double best = std::isfinite(c.spread_none) ? c.spread_none * (1 - min_gain) : -1;
  for (double s : candidates) {
    const double v = spread(s);
    c.tried.push_back(s);
    c.tried_spread.push_back(v);
    if (!(std::isfinite(v) && v < best)) break;  // no better than the last: larger sigmas are not tried
    best = v * (1 - next_gain);
    c.sigma = s;
    c.spread = v;
  }
  return c;
}

std::string describe_highpass_choice(const HighpassChoice& h, const std::string& images, bool given, const std::string& sampled,
                                     const std::string& measure, const std::string& not_estimated) {
  auto px = [](double v) { return std::isfinite(v) ? format_number(std::round(v * 1e4) / 1e4) + " px" : std::string("undefined"); };
  std::string s = h.sigma > 0 ? "local mean (Gaussian of " + format_number(h.sigma) + " px) subtracted from " + images + " before refinement"
                              : std::string("none");
  if (given) return s + " (--highpass)";
  if (h.samples == 0) return s + " " + not_estimated;
  s += " (estimated on " + std::to_string(h.samples) + " " + sampled + ": " + measure + " " + px(h.spread_none) + " unfiltered";
  const bool paired = h.tried_reference.size() == h.tried.size() && h.tried_common.size() == h.tried.size() && !h.tried.empty();
  for (size_t k = 0; k < h.tried.size(); ++k)
    s += paired ? "; at " + format_number(h.tried[k]) + " px " + px(h.tried_reference[k]) + " -> " + px(h.tried_spread[k]) + " over the " +
                      std::to_string(h.tried_common[k]) + " views both refined"
                : ", " + px(h.tried_spread[k]) + " at " + format_number(h.tried[k]) + " px";
  if (paired) s += "; kept where it falls by " + format_number(h.paired_gain * 100) + "%";
  return s + ")";
}

}  // namespace tpkit
