#include "tpkit/core/coverage_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"

namespace tpkit {

namespace {
constexpr int kThumb = 64;          // thumbnail cells along the longer side
constexpr double kMaxPixels = 4e8;  // larger images get no thumbnail (read time), said in the note

// Block means of band 0 on a kThumb grid, stretched 2-98% to grey levels 0..255; empty when unreadable.
// `w` x `h`: the size the points' file gives the image (0: none); the image's own, from its file, decides
// whether it is read: a header line is no measure of what a read costs.
std::vector<int> thumbnail(const std::string& path, long w, long h, int& tx, int& ty, std::string& why) {
  std::vector<int> grey;
  ImageInfo info;
  try {
    info = image_info(path);
  } catch (const InputError& e) {
    why = e.reason() == "no such file" ? "no thumbnail: image not found" : "no thumbnail: unreadable";
    return grey;
  }
  if (w > 0 && h > 0 && (info.width != w || info.height != h)) {
    why = "no thumbnail: the image is " + std::to_string(info.width) + " x " + std::to_string(info.height) + ", not " +
          std::to_string(w) + " x " + std::to_string(h);
    return grey;
  }
  if (static_cast<double>(info.width) * info.height > kMaxPixels) {
    why = "no thumbnail: image too large";
    return grey;
  }
  Raster r;
  try {
    r = read_region(path, 0, 0, 0, info.width, info.height);
  } catch (const std::exception& e) {
    why = "no thumbnail: unreadable";
    return grey;
  }
  const long ext = std::max(r.width, r.height);
  tx = std::max(1, static_cast<int>(std::lround(kThumb * double(r.width) / ext)));
  ty = std::max(1, static_cast<int>(std::lround(kThumb * double(r.height) / ext)));
  std::vector<double> sum(tx * ty, 0.0), cnt(tx * ty, 0.0);
  for (long y = 0; y < r.height; ++y)
    for (long x = 0; x < r.width; ++x) {
      int k = static_cast<int>(y * ty / r.height) * tx + static_cast<int>(x * tx / r.width);
      sum[k] += r.at(x, y), cnt[k] += 1;
    }
  std::vector<double> mean(tx * ty);
  for (size_t k = 0; k < mean.size(); ++k) mean[k] = cnt[k] ? sum[k] / cnt[k] : 0;
  std::vector<double> s = mean;
  std::sort(s.begin(), s.end());
  double lo = s[s.size() * 2 / 100], hi = s[std::min(s.size() - 1, s.size() * 98 / 100)];
  if (!(hi > lo)) hi = lo + 1;
  for (double m : mean) grey.push_back(std::clamp(static_cast<int>(255 * (m - lo) / (hi - lo)), 0, 255));
  return grey;
}
}  // namespace

SvgPlot coverage_figure(const std::vector<CoverageView>& views, const std::string& title, int cells) {
  const double pw = 300, top = 78, left = 75, hgap = 75;
  const int n = static_cast<int>(views.size());
  // counts per cell, and the colour scale's top (the largest count of any view)
  struct Grid {
    double x0, y0, cw, ch;
    int nx, ny;
    std::vector<long> count;
  };
  std::vector<Grid> grids;
  long cmax = 1;
  for (const auto& v : views) {
    double x1 = v.width - 0.5, y1 = v.height - 0.5;
    if (!(v.width > 0 && v.height > 0)) {
      x1 = y1 = 1;
      for (size_t i = 0; i < v.x.size(); ++i) x1 = std::max(x1, v.x[i] + 0.5), y1 = std::max(y1, v.y[i] + 0.5);
    }
    Grid g{-0.5, -0.5, 0, 0, 0, 0, {}};
    const double ext = std::max(x1 - g.x0, y1 - g.y0);
    g.nx = std::max(1, static_cast<int>(std::lround(cells * (x1 - g.x0) / ext)));
    g.ny = std::max(1, static_cast<int>(std::lround(cells * (y1 - g.y0) / ext)));
    g.cw = (x1 - g.x0) / g.nx, g.ch = (y1 - g.y0) / g.ny;
    g.count.assign(g.nx * g.ny, 0);
    for (size_t i = 0; i < v.x.size(); ++i) {
      if (!std::isfinite(v.x[i]) || !std::isfinite(v.y[i])) continue;
      int cx = std::clamp(static_cast<int>((v.x[i] - g.x0) / g.cw), 0, g.nx - 1);
      int cy = std::clamp(static_cast<int>((v.y[i] - g.y0) / g.ch), 0, g.ny - 1);
      cmax = std::max(cmax, ++g.count[cy * g.nx + cx]);
    }
    grids.push_back(std::move(g));
  }
  const double cbar_x = left + n * pw + (n - 1) * hgap + 20;
  SvgPlot plot(cbar_x + 110, top + pw + 95, title);
  for (int k = 0; k < n; ++k) {
    const Grid& g = grids[k];
    const double x1 = g.x0 + g.nx * g.cw, y1 = g.y0 + g.ny * g.ch;
    long with = 0, used = 0;
    for (long c : g.count) with += c > 0, used += c;
    std::string why;
    int tx = 0, ty = 0;
    const auto grey = thumbnail(views[k].image, static_cast<long>(views[k].width), static_cast<long>(views[k].height), tx, ty, why);
    SvgPlot::PanelSpec s = SvgPlot::spec(left + k * (pw + hgap), top, pw, pw, g.x0, x1, g.y0, y1, views[k].title, "x (px)", "y (px)");
    s.y_down = s.equal_aspect = true;
    char note[160];
    std::snprintf(note, sizeof note, "%ld point%s; %ld of %d cells without any (%.0f%%)%s%s", used, used == 1 ? "" : "s",
                  static_cast<long>(g.count.size()) - with, g.nx * g.ny, 100.0 * (g.count.size() - with) / g.count.size(),
                  why.empty() ? "" : "; ", why.c_str());
    s.note = note;
    const int p = plot.panel(s);
    if (!grey.empty()) {
      const double bw = (x1 - g.x0) / tx, bh = (y1 - g.y0) / ty;
      for (int yy = 0; yy < ty; ++yy)
        for (int xx = 0; xx < tx; ++xx) {
          char c[8];
          int v = grey[yy * tx + xx];
          std::snprintf(c, sizeof c, "#%02x%02x%02x", v, v, v);
          plot.cell(p, g.x0 + xx * bw, g.y0 + yy * bh, g.x0 + (xx + 1.4) * bw, g.y0 + (yy + 1.4) * bh, c);  // overlap: no seams
        }
    }
    for (int cy = 0; cy < g.ny; ++cy)
      for (int cx = 0; cx < g.nx; ++cx) {
        const long c = g.count[cy * g.nx + cx];
        const double a = g.x0 + cx * g.cw, b = g.y0 + cy * g.ch;
        if (c > 0)
          plot.cell(p, a, b, a + g.cw, b + g.ch, SvgPlot::viridis(static_cast<double>(c) / cmax), 0.55);
        else
          plot.polyline(p, {a + 0.06 * g.cw, a + 0.94 * g.cw, a + 0.94 * g.cw, a + 0.06 * g.cw, a + 0.06 * g.cw},
                        {b + 0.06 * g.ch, b + 0.06 * g.ch, b + 0.94 * g.ch, b + 0.94 * g.ch, b + 0.06 * g.ch}, "#e4002b", 1.2);
      }
  }
  plot.colorbar(cbar_x, top, 16, pw, 0, static_cast<double>(cmax), "points per cell");
  plot.legend_at(left, top + pw + 75,
                 {{"cell tinted by its number of points (over the image's thumbnail)", SvgPlot::viridis(0.6), SvgPlot::Mark::box},
                  {"cell without any point", "#e4002b", SvgPlot::Mark::frame}});
  return plot;
}

}  // namespace tpkit
