#include "tpkit/core/residual_field.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tpkit {

namespace {
// Value at fraction q of the sorted values (nearest rank below).
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}
// The largest 1, 2 or 5 x 10^k not above v.
double nice_below(double v) {
  if (!(v > 0)) return 1;
  double m = std::pow(10.0, std::floor(std::log10(v)));
  for (double f : {5.0, 2.0, 1.0})
    if (f * m <= v * (1 + 1e-9)) return f * m;
  return m;
}
const char* kFew = "#d4d4d4";
const char* kSingle = "#444";
}  // namespace

std::string format_rmse(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

ResidualSummary summarize_residuals(const std::vector<double>& dx, const std::vector<double>& dy) {
  ResidualSummary s;
  s.n = static_cast<long>(std::min(dx.size(), dy.size()));
  if (s.n == 0) return s;
  std::vector<double> len(s.n);
  double sum = 0;
  for (long i = 0; i < s.n; ++i) {
    double l2 = dx[i] * dx[i] + dy[i] * dy[i];
    sum += l2;
    len[i] = std::sqrt(l2);
  }
  s.rmse = std::sqrt(sum / s.n);
  std::sort(len.begin(), len.end());
  s.median = s.n % 2 ? len[s.n / 2] : 0.5 * (len[s.n / 2 - 1] + len[s.n / 2]);
  s.p90 = len[std::min<long>(s.n - 1, static_cast<long>(std::ceil(0.9 * s.n)) - 1)];
  return s;
}

std::string residual_summary_text(const ResidualSummary& s) {
  return "RMSE " + format_rmse(s.rmse) + " px \u00b7 median " + format_rmse(s.median) + " \u00b7 p90 " +
         format_rmse(s.p90) + " \u00b7 n " + std::to_string(s.n);
}

void view_extent(const ResidualView& v, double& x0, double& y0, double& x1, double& y1) {
  if (v.width > 0 && v.height > 0) {
    x0 = -0.5, y0 = -0.5, x1 = v.width - 0.5, y1 = v.height - 0.5;
    return;
  }
  x0 = y0 = 1e300, x1 = y1 = -1e300;
  for (size_t i = 0; i < v.x.size(); ++i) {
    x0 = std::min(x0, v.x[i]), x1 = std::max(x1, v.x[i]);
    y0 = std::min(y0, v.y[i]), y1 = std::max(y1, v.y[i]);
  }
  if (!(x1 > x0)) x0 = 0, x1 = 1;
  if (!(y1 > y0)) y0 = 0, y1 = 1;
  // round out to whole cells of the points' extent
  x0 -= 0.5, y0 -= 0.5, x1 += 0.5, y1 += 0.5;
}

ResidualGrid residual_grid(const ResidualView& v, int cells) {
  double x0, y0, x1, y1;
  view_extent(v, x0, y0, x1, y1);
  ResidualGrid g;
  const double ext = std::max(x1 - x0, y1 - y0);
  g.nx = std::max(1, static_cast<int>(std::lround(cells * (x1 - x0) / ext)));
  g.ny = std::max(1, static_cast<int>(std::lround(cells * (y1 - y0) / ext)));
  g.cw = (x1 - x0) / g.nx;
  g.ch = (y1 - y0) / g.ny;
  g.mx.assign(g.nx * g.ny, 0.0);
  g.my.assign(g.nx * g.ny, 0.0);
  g.count.assign(g.nx * g.ny, 0);
  for (size_t i = 0; i < v.x.size(); ++i) {
    int cx = std::clamp(static_cast<int>((v.x[i] - x0) / g.cw), 0, g.nx - 1);
    int cy = std::clamp(static_cast<int>((v.y[i] - y0) / g.ch), 0, g.ny - 1);
    int k = cy * g.nx + cx;
    g.mx[k] += v.dx[i], g.my[k] += v.dy[i], ++g.count[k];
  }
  for (size_t k = 0; k < g.count.size(); ++k)
    if (g.count[k] > 0) g.mx[k] /= g.count[k], g.my[k] /= g.count[k];
  return g;
}

FieldScale field_scale(const std::vector<ResidualView>& views, int cells, long min_count) {
  FieldScale s;
  s.cells = cells;
  s.min_count = min_count;
  std::vector<double> mags, lens;
  double cell = 1e300;
  for (const auto& v : views) {
    if (v.x.empty()) continue;  // a hole in a figure's grid, or a view without points: no cell size
    ResidualGrid g = residual_grid(v, cells);
    cell = std::min(cell, std::min(g.cw, g.ch));
    for (size_t k = 0; k < g.count.size(); ++k)
      if (g.count[k] >= min_count) mags.push_back(std::hypot(g.mx[k], g.my[k]));
    for (size_t i = 0; i < v.dx.size(); ++i) lens.push_back(std::hypot(v.dx[i], v.dy[i]));
  }
  if (!(cell < 1e300)) cell = 1;
  // cells: the 95th percentile of the cell means spans 90% of a cell; no cells: the single vectors' p90
  double ref = mags.empty() ? quantile(lens, 0.9) : quantile(mags, 0.95);
  if (!(ref > 0)) ref = 1;
  s.exaggeration = 0.9 * cell / ref;
  s.vmax = mags.empty() ? ref : std::max(quantile(mags, 0.99), 1e-12);
  s.clip = std::max(quantile(lens, s.clip_percentile / 100), 1e-12);
  s.key = nice_below(ref);
  return s;
}

std::string exaggeration_text(const FieldScale& s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", s.exaggeration);
  return std::string("vectors \u00d7") + b;
}

void draw_residual_field(SvgPlot& plot, int p, const ResidualView& v, const FieldScale& s) {
  const ResidualGrid g = residual_grid(v, s.cells);
  double x0, y0, x1, y1;
  view_extent(v, x0, y0, x1, y1);
  const double E = s.exaggeration;
  // cells: coloured by the mean's magnitude, or grey (few points)
  for (int cy = 0; cy < g.ny; ++cy)
    for (int cx = 0; cx < g.nx; ++cx) {
      const int k = cy * g.nx + cx;
      if (g.count[k] == 0) continue;
      const double a = x0 + cx * g.cw, b = y0 + cy * g.ch;
      const bool few = g.count[k] < s.min_count;
      plot.cell(p, a, b, a + g.cw, b + g.ch, few ? kFew : SvgPlot::viridis(std::hypot(g.mx[k], g.my[k]) / s.vmax));
    }
  plot.polyline(p, {x0, x1, x1, x0, x0}, {y0, y0, y1, y1, y0}, "#888", 0.8);  // the image's edge
  // mean vectors from the cell centres: white on the dark half of the colour map, black on the light half
  for (int cy = 0; cy < g.ny; ++cy)
    for (int cx = 0; cx < g.nx; ++cx) {
      const int k = cy * g.nx + cx;
      if (g.count[k] < s.min_count) continue;
      const bool dark = std::hypot(g.mx[k], g.my[k]) / s.vmax < 0.55;
      plot.arrow(p, x0 + (cx + 0.5) * g.cw, y0 + (cy + 0.5) * g.ch, E * g.mx[k], E * g.my[k], dark ? "white" : "black",
                 1.3);
    }
  // single vectors where they are few, longer ones than the clip percentile shortened to it and ringed
  std::vector<double> rx, ry;
  for (size_t i = 0; i < v.x.size(); ++i) {
    int cx = std::clamp(static_cast<int>((v.x[i] - x0) / g.cw), 0, g.nx - 1);
    int cy = std::clamp(static_cast<int>((v.y[i] - y0) / g.ch), 0, g.ny - 1);
    if (g.count[cy * g.nx + cx] >= s.min_count) continue;
    double dx = v.dx[i], dy = v.dy[i], l = std::hypot(dx, dy);
    if (l > s.clip) {
      dx *= s.clip / l, dy *= s.clip / l;
      rx.push_back(v.x[i] + E * dx), ry.push_back(v.y[i] + E * dy);
    }
    plot.arrow(p, v.x[i], v.y[i], E * dx, E * dy, kSingle, 0.7);
  }
  plot.points(p, rx, ry, kSingle, 2.2, "ring");
}

void field_legend(SvgPlot& plot, double x, double y, const FieldScale& s) {
  // the key arrow drawn to the figure's scale, then the words
  const double kx = x, ky = y - 4;
  // key length in page units is not known here (panels may differ): it is stated, not drawn to scale
  (void)kx, (void)ky;
  plot.legend_at(x, y,
                 {{exaggeration_text(s) + " (one scale for every panel): cell mean from the cell centre (white on dark cells)", "black",
                   SvgPlot::Mark::arrow},
                  {"cell with < " + std::to_string(s.min_count) + " points: its vectors one by one", kFew,
                   SvgPlot::Mark::box},
                  {"longer than p" + format_rmse(s.clip_percentile) + " = " + format_rmse(s.clip) +
                       " px or past the edge: cut",
                   kSingle, SvgPlot::Mark::ring}});
}

void draw_length_histogram(SvgPlot& plot, double left, double top, double width, double height,
                           const std::vector<HistogramSet>& sets, const std::string& title) {
  std::vector<double> all;
  size_t nmax = 1;
  for (const auto& st : sets) {
    all.insert(all.end(), st.length.begin(), st.length.end());
    nmax = std::max(nmax, st.length.size());
  }
  double top_len = quantile(all, 0.995);
  if (!(top_len > 0)) top_len = 1;
  top_len = SvgPlot::ticks(0, top_len, 5).size() > 1 ? [&] {
    auto t = SvgPlot::ticks(0, top_len, 5);
    double st = t[1] - t[0];
    return std::ceil(top_len / st - 1e-9) * st;
  }()
                                                       : top_len;
  const int bins = 40;
  std::vector<double> edges(bins + 1);
  for (int b = 0; b <= bins; ++b) edges[b] = top_len * b / bins;
  const double ymin = std::pow(10.0, std::floor(std::log10(0.5 / nmax)));
  SvgPlot::PanelSpec hs = SvgPlot::spec(left, top, width, height, 0, top_len, ymin, 1.0, title,
                                        "|r| (px); the last bin holds all beyond", "fraction of the set's residuals");
  hs.log_y = true;
  int h = plot.panel(hs);
  std::vector<SvgPlot::LegendEntry> leg;
  for (size_t k = 0; k < sets.size(); ++k) {
    std::vector<double> f(bins, 0.0);
    for (double l : sets[k].length) f[std::min(bins - 1, static_cast<int>(l / top_len * bins))] += 1;
    for (double& c : f) c /= std::max<size_t>(1, sets[k].length.size());
    if (k == 0) {
      plot.bars(h, edges, f, sets[k].color);
      leg.push_back({sets[k].label + " (n " + std::to_string(sets[k].length.size()) + ")", sets[k].color, SvgPlot::Mark::box});
    } else {
      std::vector<double> sx, sy;
      for (int b = 0; b < bins; ++b) {
        sx.push_back(edges[b]), sy.push_back(f[b]);
        sx.push_back(edges[b + 1]), sy.push_back(f[b]);
      }
      plot.polyline(h, sx, sy, sets[k].color, 1.8);
      leg.push_back({sets[k].label + " (n " + std::to_string(sets[k].length.size()) + ")", sets[k].color, SvgPlot::Mark::line});
    }
  }
  plot.legend(h, leg);
}

SvgPlot residual_figure(const std::vector<ResidualView>& views, int cols, const std::vector<HistogramSet>& hist,
                        const std::string& title,
                        const std::function<void(SvgPlot&, int, size_t, const FieldScale&)>& extra,
                        const std::vector<SvgPlot::LegendEntry>& more_legend) {
  const int n = static_cast<int>(views.size());
  cols = std::max(1, std::min(cols, std::max(1, n)));
  const int rows = std::max(1, (n + cols - 1) / cols);
  const double pw = 320, top = 78, left = 75, hgap = 75, vgap = 85;
  const double cbar_x = left + cols * pw + (cols - 1) * hgap + 20, hist_x = cbar_x + 130;
  const double height = top + rows * pw + (rows - 1) * vgap + (more_legend.empty() ? 95 : 115);
  const FieldScale fs = field_scale(views);
  SvgPlot plot(hist.empty() ? cbar_x + 110 : hist_x + pw + 30, height, title);
  for (int k = 0; k < n; ++k) {
    if (views[k].title.empty() && views[k].x.empty()) continue;  // a hole in the grid
    double x0, y0, x1, y1;
    view_extent(views[k], x0, y0, x1, y1);
    SvgPlot::PanelSpec spec = SvgPlot::spec(left + (k % cols) * (pw + hgap), top + (k / cols) * (pw + vgap), pw, pw, x0,
                                            x1, y0, y1, views[k].title, "x (px)", "y (px)");
    spec.y_down = spec.equal_aspect = true;
    spec.note = residual_summary_text(summarize_residuals(views[k].dx, views[k].dy));
    const int p = plot.panel(spec);
    draw_residual_field(plot, p, views[k], fs);
    if (extra) extra(plot, p, static_cast<size_t>(k), fs);
  }
  plot.colorbar(cbar_x, top, 16, pw, 0, fs.vmax, "|cell mean residual| (px)");
  const double legend_y = height - (more_legend.empty() ? 18 : 38);
  field_legend(plot, left, legend_y, fs);
  if (!more_legend.empty()) plot.legend_at(left, legend_y + 22, more_legend);
  if (!hist.empty()) draw_length_histogram(plot, hist_x, top, pw, pw, hist, "residual length, all views");
  return plot;
}

}  // namespace tpkit
