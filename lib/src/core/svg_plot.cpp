#include "tpkit/core/svg_plot.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/version.hpp"

namespace tpkit {

namespace {
// Each plot of a process numbers its clip paths apart: several SVGs inlined in one HTML page share one
// id space (tp-report).
std::atomic<int> plots_made{0};
std::string clip_id(int plot, int p) { return "clip" + std::to_string(plot) + "-" + std::to_string(p); }
std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}
std::string tick_label(double v, double step) {
  char b[32];
  int dec = 0;  // the decimals that write the step exactly (0.025: 3, not 2)
  while (dec < 6 && std::fabs(step * std::pow(10.0, dec) - std::round(step * std::pow(10.0, dec))) > 1e-6 * step * std::pow(10.0, dec))
    ++dec;
  if (std::fabs(v) >= 1e5 || (std::fabs(v) < 1e-3 && v != 0 && step < 1e-3))
    std::snprintf(b, sizeof b, "%.3g", v);
  else
    std::snprintf(b, sizeof b, "%.*f", std::min(dec, 6), v);
  return b;
}
}  // namespace

std::string svg_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '&') o += "&amp;";
    else if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '"') o += "&quot;";
    else o += c;
  }
  return o;
}

SvgPlot::SvgPlot(double width, double height, std::string title)
    : width_(width), height_(height), id_(plots_made++) {
  if (!title.empty()) page_text(width / 2, 22, title, 15, "middle");
}

std::vector<double> SvgPlot::ticks(double lo, double hi, int target) {
  std::vector<double> t;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return t;
  double raw = (hi - lo) / std::max(1, target);
  double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step) t.push_back(std::fabs(v) < 1e-12 * step ? 0 : v);
  return t;
}

std::vector<double> SvgPlot::log_ticks(double lo, double hi) {
  std::vector<double> t;
  if (!(hi > lo) || !(lo > 0) || !std::isfinite(hi)) return t;
  int e0 = static_cast<int>(std::floor(std::log10(lo) + 1e-9)), e1 = static_cast<int>(std::ceil(std::log10(hi) - 1e-9));
  const bool few = e1 - e0 < 3;
  for (int e = e0; e <= e1; ++e)
    for (double m : few ? std::vector<double>{1, 2, 5} : std::vector<double>{1}) {
      double v = m * std::pow(10.0, e);
      if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) t.push_back(v);
    }
  return t;
}

std::string SvgPlot::viridis(double t) {
  // viridis (matplotlib) sampled at 9 points, linear in between
  static const double c[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},  {44, 113, 142}, {33, 144, 141},
                                 {39, 173, 129}, {92, 200, 99},  {170, 220, 50}, {253, 231, 37}};
  if (!std::isfinite(t)) t = 0;
  t = std::clamp(t, 0.0, 1.0) * 8;
  int i = std::min(7, static_cast<int>(t));
  double f = t - i;
  char b[8];
  std::snprintf(b, sizeof b, "#%02x%02x%02x", static_cast<int>(std::lround(c[i][0] + f * (c[i + 1][0] - c[i][0]))),
                static_cast<int>(std::lround(c[i][1] + f * (c[i + 1][1] - c[i][1]))),
                static_cast<int>(std::lround(c[i][2] + f * (c[i + 1][2] - c[i][2]))));
  return b;
}

int SvgPlot::panel(PanelSpec s) {
  if (s.log_y && !(s.ymin > 0)) s.ymin = 1e-3 * std::max(1.0, s.ymax);
  if (!(s.xmax > s.xmin)) { s.xmin -= 0.5; s.xmax += 0.5; }
  if (!(s.ymax > s.ymin)) { s.ymin = s.log_y ? s.ymin : s.ymin - 0.5; s.ymax = s.log_y ? 10 * s.ymin : s.ymax + 0.5; }
  const double yspan = s.log_y ? std::log10(s.ymax / s.ymin) : s.ymax - s.ymin;
  Panel p{s, s.width / (s.xmax - s.xmin), s.height / yspan};
  if (s.equal_aspect && !s.log_y) {
    double k = std::min(p.sx, p.sy);
    double cx = 0.5 * (s.xmin + s.xmax), cy = 0.5 * (s.ymin + s.ymax);
    p.s.xmin = cx - 0.5 * s.width / k;
    p.s.xmax = cx + 0.5 * s.width / k;
    p.s.ymin = cy - 0.5 * s.height / k;
    p.s.ymax = cy + 0.5 * s.height / k;
    p.sx = p.sy = k;
  }
  panels_.push_back(p);
  int idx = static_cast<int>(panels_.size()) - 1;
  const auto& q = panels_.back().s;
  std::ostringstream o;
  o << "<clipPath id=\"" << clip_id(id_, idx) << "\"><rect x=\"" << num(q.left) << "\" y=\"" << num(q.top) << "\" width=\""
    << num(q.width) << "\" height=\"" << num(q.height) << "\"/></clipPath>\n";
  o << "<rect class=\"panel\" data-p=\"" << idx << "\" x=\"" << num(q.left) << "\" y=\"" << num(q.top) << "\" width=\""
    << num(q.width) << "\" height=\"" << num(q.height) << "\" fill=\"white\" stroke=\"#333\"/>\n";
  auto xt = ticks(q.xmin, q.xmax), yt = q.log_y ? log_ticks(q.ymin, q.ymax) : ticks(q.ymin, q.ymax);
  double xs = xt.size() > 1 ? xt[1] - xt[0] : 1, ys = yt.size() > 1 ? yt[1] - yt[0] : 1;
  for (double v : xt) {
    double X = px(panels_.back(), v);
    o << "<line x1=\"" << num(X) << "\" y1=\"" << num(q.top + q.height) << "\" x2=\"" << num(X) << "\" y2=\""
      << num(q.top + q.height + 5) << "\" stroke=\"#333\"/>\n";
    o << "<line x1=\"" << num(X) << "\" y1=\"" << num(q.top) << "\" x2=\"" << num(X) << "\" y2=\"" << num(q.top + q.height)
      << "\" stroke=\"#ddd\" stroke-width=\"0.5\"/>\n";
    o << "<text x=\"" << num(X) << "\" y=\"" << num(q.top + q.height + 17) << "\" font-size=\"10\" text-anchor=\"middle\">"
      << tick_label(v, xs) << "</text>\n";
  }
  for (double v : yt) {
    double Y = py(panels_.back(), v);
    o << "<line x1=\"" << num(q.left - 5) << "\" y1=\"" << num(Y) << "\" x2=\"" << num(q.left) << "\" y2=\"" << num(Y)
      << "\" stroke=\"#333\"/>\n";
    o << "<line x1=\"" << num(q.left) << "\" y1=\"" << num(Y) << "\" x2=\"" << num(q.left + q.width) << "\" y2=\"" << num(Y)
      << "\" stroke=\"#ddd\" stroke-width=\"0.5\"/>\n";
    o << "<text x=\"" << num(q.left - 8) << "\" y=\"" << num(Y + 3.5) << "\" font-size=\"10\" text-anchor=\"end\">"
      << (q.log_y ? tick_label(v, std::min(1.0, v)) : tick_label(v, ys)) << "</text>\n";
  }
  const double title_y = q.note.empty() ? q.top - 8 : q.top - 22;
  if (!q.title.empty())
    o << "<text x=\"" << num(q.left + q.width / 2) << "\" y=\"" << num(title_y)
      << "\" font-size=\"12\" text-anchor=\"middle\" font-weight=\"bold\">" << svg_escape(q.title) << "</text>\n";
  if (!q.note.empty())
    o << "<text class=\"note\" x=\"" << num(q.left + q.width / 2) << "\" y=\"" << num(q.top - 7)
      << "\" font-size=\"11\" text-anchor=\"middle\">" << svg_escape(q.note) << "</text>\n";
  if (!q.xlabel.empty())
    o << "<text x=\"" << num(q.left + q.width / 2) << "\" y=\"" << num(q.top + q.height + 34)
      << "\" font-size=\"11\" text-anchor=\"middle\">" << svg_escape(q.xlabel) << "</text>\n";
  if (!q.ylabel.empty())
    o << "<text transform=\"translate(" << num(q.left - 45) << "," << num(q.top + q.height / 2)
      << ") rotate(-90)\" font-size=\"11\" text-anchor=\"middle\">" << svg_escape(q.ylabel) << "</text>\n";
  body_ += o.str();
  return idx;
}

double SvgPlot::px(const Panel& p, double x) const { return p.s.left + (x - p.s.xmin) * p.sx; }
double SvgPlot::py(const Panel& p, double y) const {
  if (p.s.log_y) {
    double l = std::log10(std::max(y, p.s.ymin) / p.s.ymin) * p.sy;
    return p.s.top + p.s.height - l;
  }
  return p.s.y_down ? p.s.top + (y - p.s.ymin) * p.sy : p.s.top + p.s.height - (y - p.s.ymin) * p.sy;
}

SvgPlot::Box SvgPlot::panel_box(int pi) const {
  const auto& s = panels_.at(pi).s;
  return {pi, s.left, s.top, s.left + s.width, s.top + s.height};
}

void SvgPlot::record(int p, double x0, double y0, double x1, double y1) {
  marks_.push_back({p, std::min(x0, x1), std::min(y0, y1), std::max(x0, x1), std::max(y0, y1)});
}

bool SvgPlot::marks_inside(double tol) const {
  for (const auto& m : marks_) {
    if (m.panel < 0) continue;
    Box b = panel_box(m.panel);
    if (m.x0 < b.x0 - tol || m.y0 < b.y0 - tol || m.x1 > b.x1 + tol || m.y1 > b.y1 + tol) return false;
  }
  return true;
}

namespace {
// Every mark of a panel sits in a group naming the panel and clipped to it (tests/tools/figure_check.sh
// reads data-p to check the marks against the panel's box).
std::string open_marks(int plot, int p) {
  return "<g data-p=\"" + std::to_string(p) + "\" clip-path=\"url(#" + clip_id(plot, p) + ")\">\n";
}

// Page point clamped into a panel's box.
double clampd(double v, double lo, double hi) { return std::min(std::max(v, lo), hi); }
}  // namespace

void SvgPlot::polyline(int pi, const std::vector<double>& x, const std::vector<double>& y, const std::string& color,
                       double width) {
  const Panel& p = panels_.at(pi);
  Box b = panel_box(pi);
  std::ostringstream o;
  o << open_marks(id_, pi) << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\"" << width << "\" stroke-linejoin=\"round\" points=\"";
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (size_t i = 0; i < std::min(x.size(), y.size()); ++i)
    if (std::isfinite(x[i]) && std::isfinite(y[i])) {
      double X = clampd(px(p, x[i]), b.x0, b.x1), Y = clampd(py(p, y[i]), b.y0, b.y1);
      o << num(X) << ',' << num(Y) << ' ';
      x0 = std::min(x0, X), y0 = std::min(y0, Y), x1 = std::max(x1, X), y1 = std::max(y1, Y);
    }
  o << "\"/>\n</g>\n";
  if (x1 >= x0) record(pi, x0, y0, x1, y1);
  body_ += o.str();
}

void SvgPlot::points(int pi, const std::vector<double>& x, const std::vector<double>& y, const std::string& color,
                     double r, const std::string& shape) {
  const Panel& p = panels_.at(pi);
  Box b = panel_box(pi);
  std::ostringstream o;
  o << open_marks(id_, pi) << "<g fill=\"" << color << "\" stroke=\"" << color << "\">\n";
  for (size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    double X = px(p, x[i]), Y = py(p, y[i]);
    if (X - r < b.x0 || X + r > b.x1 || Y - r < b.y0 || Y + r > b.y1) {
      ++points_outside_;
      continue;
    }
    record(pi, X - r, Y - r, X + r, Y + r);
    if (shape == "cross")
      o << "<path d=\"M" << num(X - r) << ' ' << num(Y - r) << "L" << num(X + r) << ' ' << num(Y + r) << "M" << num(X - r)
        << ' ' << num(Y + r) << "L" << num(X + r) << ' ' << num(Y - r) << "\" fill=\"none\"/>\n";
    else if (shape == "ring")
      o << "<circle cx=\"" << num(X) << "\" cy=\"" << num(Y) << "\" r=\"" << num(r) << "\" fill=\"none\"/>\n";
    else if (shape == "square")
      o << "<rect x=\"" << num(X - r) << "\" y=\"" << num(Y - r) << "\" width=\"" << num(2 * r) << "\" height=\""
        << num(2 * r) << "\" fill=\"none\"/>\n";
    else
      o << "<circle cx=\"" << num(X) << "\" cy=\"" << num(Y) << "\" r=\"" << num(r) << "\"/>\n";
  }
  o << "</g>\n</g>\n";
  body_ += o.str();
}

bool SvgPlot::arrow(int pi, double x, double y, double dx, double dy, const std::string& color, double width) {
  const Panel& p = panels_.at(pi);
  Box b = panel_box(pi);
  double X0 = px(p, x), Y0 = py(p, y), X1 = px(p, x + dx), Y1 = py(p, y + dy);
  if (X0 < b.x0 || X0 > b.x1 || Y0 < b.y0 || Y0 > b.y1 || !std::isfinite(X1) || !std::isfinite(Y1)) return false;
  // cut at the panel edge (Liang-Barsky on the segment's parameter)
  const double m = 2.5;  // room for the cut mark
  double t = 1;
  auto cut = [&](double d, double from, double lo, double hi) {
    if (d > 0 && from + t * d > hi - m) t = std::max(0.0, (hi - m - from) / d);
    if (d < 0 && from + t * d < lo + m) t = std::max(0.0, (lo + m - from) / d);
  };
  cut(X1 - X0, X0, b.x0, b.x1);
  cut(Y1 - Y0, Y0, b.y0, b.y1);
  const bool whole = t >= 1;
  X1 = X0 + t * (X1 - X0);
  Y1 = Y0 + t * (Y1 - Y0);
  double L = std::hypot(X1 - X0, Y1 - Y0);
  std::ostringstream o;
  o << open_marks(id_, pi) << "<line x1=\"" << num(X0) << "\" y1=\"" << num(Y0) << "\" x2=\"" << num(X1) << "\" y2=\"" << num(Y1)
    << "\" stroke=\"" << color << "\" stroke-width=\"" << width << "\"/>\n";
  record(pi, X0, Y0, X1, Y1);
  if (!whole) {
    o << "<circle class=\"cut\" cx=\"" << num(X1) << "\" cy=\"" << num(Y1) << "\" r=\"2.2\" fill=\"none\" stroke=\"" << color
      << "\" stroke-width=\"1\"/>\n";
    record(pi, X1 - 2.2, Y1 - 2.2, X1 + 2.2, Y1 + 2.2);
  } else if (L > 3) {
    double ux = (X1 - X0) / L, uy = (Y1 - Y0) / L, h = std::min(6.0, 0.35 * L);
    o << "<path d=\"M" << num(X1) << ' ' << num(Y1) << "L" << num(X1 - h * ux - 0.5 * h * uy) << ' '
      << num(Y1 - h * uy + 0.5 * h * ux) << "L" << num(X1 - h * ux + 0.5 * h * uy) << ' ' << num(Y1 - h * uy - 0.5 * h * ux)
      << "Z\" fill=\"" << color << "\"/>\n";
  }
  o << "</g>\n";
  body_ += o.str();
  return whole;
}

void SvgPlot::cell(int pi, double x0, double y0, double x1, double y1, const std::string& fill, double opacity) {
  const Panel& p = panels_.at(pi);
  Box b = panel_box(pi);
  double X0 = clampd(px(p, x0), b.x0, b.x1), X1 = clampd(px(p, x1), b.x0, b.x1);
  double Y0 = clampd(py(p, y0), b.y0, b.y1), Y1 = clampd(py(p, y1), b.y0, b.y1);
  if (X0 > X1) std::swap(X0, X1);
  if (Y0 > Y1) std::swap(Y0, Y1);
  std::ostringstream o;
  o << open_marks(id_, pi) << "<rect x=\"" << num(X0) << "\" y=\"" << num(Y0) << "\" width=\"" << num(X1 - X0) << "\" height=\""
    << num(Y1 - Y0) << "\" fill=\"" << fill << "\" shape-rendering=\"crispEdges\"";  // no seams between cells
  if (opacity < 1) o << " fill-opacity=\"" << opacity << "\"";
  o << "/>\n</g>\n";
  record(pi, X0, Y0, X1, Y1);
  body_ += o.str();
}

void SvgPlot::bars(int pi, const std::vector<double>& edges, const std::vector<double>& counts, const std::string& color) {
  const Panel& p = panels_.at(pi);
  Box b = panel_box(pi);
  std::ostringstream o;
  o << open_marks(id_, pi);
  for (size_t i = 0; i + 1 < edges.size() && i < counts.size(); ++i) {
    if (!(counts[i] > (p.s.log_y ? p.s.ymin : 0))) continue;
    double X0 = clampd(px(p, edges[i]), b.x0, b.x1), X1 = clampd(px(p, edges[i + 1]), b.x0, b.x1);
    double Y0 = b.y1, Y1 = clampd(py(p, counts[i]), b.y0, b.y1);
    o << "<rect x=\"" << num(std::min(X0, X1)) << "\" y=\"" << num(std::min(Y0, Y1)) << "\" width=\"" << num(std::fabs(X1 - X0))
      << "\" height=\"" << num(std::fabs(Y1 - Y0)) << "\" fill=\"" << color << "\" stroke=\"white\" stroke-width=\"0.5\"/>\n";
    record(pi, X0, Y0, X1, Y1);
  }
  o << "</g>\n";
  body_ += o.str();
}

void SvgPlot::segment(int pi, double x0, double y0, double x1, double y1, const std::string& color, double width) {
  polyline(pi, {x0, x1}, {y0, y1}, color, width);
}

void SvgPlot::text(int pi, double x, double y, const std::string& s, double size, const std::string& anchor) {
  const Panel& p = panels_.at(pi);
  page_text(px(p, x), py(p, y), s, size, anchor);
}

void SvgPlot::page_text(double x, double y, const std::string& s, double size, const std::string& anchor) {
  std::ostringstream o;
  o << "<text x=\"" << num(x) << "\" y=\"" << num(y) << "\" font-size=\"" << size << "\" text-anchor=\"" << anchor << "\">"
    << svg_escape(s) << "</text>\n";
  body_ += o.str();
}

void SvgPlot::legend(int pi, const std::vector<LegendEntry>& entries) {
  const auto& s = panels_.at(pi).s;
  legend_at(s.left, s.top + s.height + (s.xlabel.empty() ? 34 : 52), entries);
}

void SvgPlot::legend_at(double x, double y, const std::vector<LegendEntry>& entries) {
  std::ostringstream o;
  o << "<g class=\"legend\">\n";
  for (const auto& e : entries) {
    const double cx = x + 10, cy = y - 4;
    switch (e.mark) {
      case Mark::dot:
        o << "<circle cx=\"" << num(cx) << "\" cy=\"" << num(cy) << "\" r=\"3\" fill=\"" << e.color << "\"/>\n";
        break;
      case Mark::cross:
        o << "<path d=\"M" << num(cx - 3.5) << ' ' << num(cy - 3.5) << "L" << num(cx + 3.5) << ' ' << num(cy + 3.5) << "M"
          << num(cx - 3.5) << ' ' << num(cy + 3.5) << "L" << num(cx + 3.5) << ' ' << num(cy - 3.5) << "\" stroke=\"" << e.color
          << "\" stroke-width=\"1.2\" fill=\"none\"/>\n";
        break;
      case Mark::ring:
        o << "<circle cx=\"" << num(cx) << "\" cy=\"" << num(cy) << "\" r=\"2.2\" fill=\"none\" stroke=\"" << e.color
          << "\"/>\n";
        break;
      case Mark::frame:
        o << "<rect x=\"" << num(cx - 6) << "\" y=\"" << num(cy - 5) << "\" width=\"12\" height=\"10\" fill=\"none\" stroke=\""
          << e.color << "\" stroke-width=\"1.2\"/>\n";
        break;
      case Mark::box:
        o << "<rect x=\"" << num(cx - 6) << "\" y=\"" << num(cy - 5) << "\" width=\"12\" height=\"10\" fill=\"" << e.color
          << "\" stroke=\"#999\" stroke-width=\"0.5\"/>\n";
        break;
      case Mark::arrow:
        o << "<line x1=\"" << num(x) << "\" y1=\"" << num(cy) << "\" x2=\"" << num(x + 16) << "\" y2=\"" << num(cy)
          << "\" stroke=\"" << e.color << "\" stroke-width=\"1.2\"/>\n<path d=\"M" << num(x + 20) << ' ' << num(cy) << "L"
          << num(x + 14) << ' ' << num(cy - 3) << "L" << num(x + 14) << ' ' << num(cy + 3) << "Z\" fill=\"" << e.color << "\"/>\n";
        break;
      case Mark::line:
        o << "<line x1=\"" << num(x) << "\" y1=\"" << num(cy) << "\" x2=\"" << num(x + 20) << "\" y2=\"" << num(cy)
          << "\" stroke=\"" << e.color << "\" stroke-width=\"2\"/>\n";
        break;
    }
    o << "<text x=\"" << num(x + 26) << "\" y=\"" << num(y) << "\" font-size=\"10\">" << svg_escape(e.label) << "</text>\n";
    x += 40 + 5.6 * e.label.size();
  }
  o << "</g>\n";
  body_ += o.str();
}

void SvgPlot::colorbar(double left, double top, double width, double height, double vmin, double vmax,
                       const std::string& label) {
  std::ostringstream o;
  const int n = 32;
  for (int i = 0; i < n; ++i) {
    double y = top + height * (n - 1 - i) / n;
    o << "<rect x=\"" << num(left) << "\" y=\"" << num(y) << "\" width=\"" << num(width) << "\" height=\""
      << num(height / n + 0.3) << "\" fill=\"" << viridis((i + 0.5) / n) << "\"/>\n";
  }
  o << "<rect x=\"" << num(left) << "\" y=\"" << num(top) << "\" width=\"" << num(width) << "\" height=\"" << num(height)
    << "\" fill=\"none\" stroke=\"#333\" stroke-width=\"0.5\"/>\n";
  if (vmax > vmin) {
    auto t = ticks(vmin, vmax, 5);
    double st = t.size() > 1 ? t[1] - t[0] : 1;
    for (double v : t) {
      double Y = top + height * (1 - (v - vmin) / (vmax - vmin));
      o << "<line x1=\"" << num(left + width) << "\" y1=\"" << num(Y) << "\" x2=\"" << num(left + width + 4) << "\" y2=\""
        << num(Y) << "\" stroke=\"#333\"/>\n<text x=\"" << num(left + width + 6) << "\" y=\"" << num(Y + 3.5)
        << "\" font-size=\"10\">" << tick_label(v, st) << "</text>\n";
    }
  }
  o << "<text transform=\"translate(" << num(left + width + 44) << "," << num(top + height / 2)
    << ") rotate(-90)\" font-size=\"11\" text-anchor=\"middle\">" << svg_escape(label) << "</text>\n";
  marks_.push_back({-1, left, top, left + width, top + height});
  body_ += o.str();
}

std::string SvgPlot::str() const {
  std::ostringstream o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- written by " << written_by() << " -->\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(width_)
    << "\" height=\"" << num(height_) << "\" viewBox=\"0 0 " << num(width_) << ' ' << num(height_)
    << "\" font-family=\"sans-serif\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << body_ << "</svg>\n";
  return o.str();
}

std::string SvgPlot::inline_svg() const {
  const std::string s = str();
  return s.substr(s.find("<svg "));
}

void SvgPlot::save(const std::string& path) const { write_file_atomic(path, str()); }

}  // namespace tpkit
