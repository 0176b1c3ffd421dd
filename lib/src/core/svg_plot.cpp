#include "tpkit/core/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/version.hpp"

namespace tpkit {

namespace {
std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}
std::string tick_label(double v, double step) {
  char b[32];
  int dec = step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
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

SvgPlot::SvgPlot(double width, double height, std::string title) : width_(width), height_(height) {
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

int SvgPlot::panel(PanelSpec s) {
  if (!(s.xmax > s.xmin)) { s.xmin -= 0.5; s.xmax += 0.5; }
  if (!(s.ymax > s.ymin)) { s.ymin -= 0.5; s.ymax += 0.5; }
  Panel p{s, s.width / (s.xmax - s.xmin), s.height / (s.ymax - s.ymin)};
  if (s.equal_aspect) {
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
  o << "<rect x=\"" << num(q.left) << "\" y=\"" << num(q.top) << "\" width=\"" << num(q.width) << "\" height=\""
    << num(q.height) << "\" fill=\"white\" stroke=\"#333\"/>\n";
  auto xt = ticks(q.xmin, q.xmax), yt = ticks(q.ymin, q.ymax);
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
      << tick_label(v, ys) << "</text>\n";
  }
  if (!q.title.empty())
    o << "<text x=\"" << num(q.left + q.width / 2) << "\" y=\"" << num(q.top - 8)
      << "\" font-size=\"12\" text-anchor=\"middle\" font-weight=\"bold\">" << svg_escape(q.title) << "</text>\n";
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
  return p.s.y_down ? p.s.top + (y - p.s.ymin) * p.sy : p.s.top + p.s.height - (y - p.s.ymin) * p.sy;
}

void SvgPlot::polyline(int pi, const std::vector<double>& x, const std::vector<double>& y, const std::string& color,
                       double width) {
  const Panel& p = panels_.at(pi);
  std::ostringstream o;
  o << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\"" << width << "\" points=\"";
  for (size_t i = 0; i < std::min(x.size(), y.size()); ++i)
    if (std::isfinite(x[i]) && std::isfinite(y[i])) o << num(px(p, x[i])) << ',' << num(py(p, y[i])) << ' ';
  o << "\"/>\n";
  body_ += o.str();
}

void SvgPlot::points(int pi, const std::vector<double>& x, const std::vector<double>& y, const std::string& color,
                     double r, const std::string& shape) {
  const Panel& p = panels_.at(pi);
  std::ostringstream o;
  o << "<g fill=\"" << color << "\" stroke=\"" << color << "\">\n";
  for (size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    double X = px(p, x[i]), Y = py(p, y[i]);
    if (shape == "cross")
      o << "<path d=\"M" << num(X - r) << ' ' << num(Y - r) << "L" << num(X + r) << ' ' << num(Y + r) << "M" << num(X - r)
        << ' ' << num(Y + r) << "L" << num(X + r) << ' ' << num(Y - r) << "\" fill=\"none\"/>\n";
    else if (shape == "square")
      o << "<rect x=\"" << num(X - r) << "\" y=\"" << num(Y - r) << "\" width=\"" << num(2 * r) << "\" height=\""
        << num(2 * r) << "\" fill=\"none\"/>\n";
    else
      o << "<circle cx=\"" << num(X) << "\" cy=\"" << num(Y) << "\" r=\"" << num(r) << "\"/>\n";
  }
  o << "</g>\n";
  body_ += o.str();
}

void SvgPlot::arrow(int pi, double x, double y, double dx, double dy, const std::string& color, double width) {
  const Panel& p = panels_.at(pi);
  double X0 = px(p, x), Y0 = py(p, y), X1 = px(p, x + dx), Y1 = py(p, y + dy);
  double L = std::hypot(X1 - X0, Y1 - Y0);
  std::ostringstream o;
  o << "<line x1=\"" << num(X0) << "\" y1=\"" << num(Y0) << "\" x2=\"" << num(X1) << "\" y2=\"" << num(Y1) << "\" stroke=\""
    << color << "\" stroke-width=\"" << width << "\"/>\n";
  if (L > 3) {
    double ux = (X1 - X0) / L, uy = (Y1 - Y0) / L, h = std::min(6.0, 0.35 * L);
    o << "<path d=\"M" << num(X1) << ' ' << num(Y1) << "L" << num(X1 - h * ux - 0.5 * h * uy) << ' '
      << num(Y1 - h * uy + 0.5 * h * ux) << "L" << num(X1 - h * ux + 0.5 * h * uy) << ' ' << num(Y1 - h * uy - 0.5 * h * ux)
      << "Z\" fill=\"" << color << "\"/>\n";
  }
  body_ += o.str();
}

void SvgPlot::bars(int pi, const std::vector<double>& edges, const std::vector<double>& counts, const std::string& color) {
  const Panel& p = panels_.at(pi);
  std::ostringstream o;
  for (size_t i = 0; i + 1 < edges.size() && i < counts.size(); ++i) {
    double X0 = px(p, edges[i]), X1 = px(p, edges[i + 1]);
    double Y0 = py(p, p.s.ymin), Y1 = py(p, counts[i]);
    o << "<rect x=\"" << num(std::min(X0, X1)) << "\" y=\"" << num(std::min(Y0, Y1)) << "\" width=\"" << num(std::fabs(X1 - X0))
      << "\" height=\"" << num(std::fabs(Y1 - Y0)) << "\" fill=\"" << color << "\" stroke=\"white\" stroke-width=\"0.5\"/>\n";
  }
  body_ += o.str();
}

void SvgPlot::segment(int pi, double x0, double y0, double x1, double y1, const std::string& color, double width) {
  const Panel& p = panels_.at(pi);
  std::ostringstream o;
  o << "<line x1=\"" << num(px(p, x0)) << "\" y1=\"" << num(py(p, y0)) << "\" x2=\"" << num(px(p, x1)) << "\" y2=\""
    << num(py(p, y1)) << "\" stroke=\"" << color << "\" stroke-width=\"" << width << "\"/>\n";
  body_ += o.str();
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

void SvgPlot::legend(int pi, const std::vector<std::pair<std::string, std::string>>& entries) {
  const Panel& p = panels_.at(pi);
  double x = p.s.left + p.s.width - 150, y = p.s.top + 14;
  std::ostringstream o;
  for (const auto& e : entries) {
    o << "<line x1=\"" << num(x) << "\" y1=\"" << num(y - 4) << "\" x2=\"" << num(x + 20) << "\" y2=\"" << num(y - 4)
      << "\" stroke=\"" << e.second << "\" stroke-width=\"2\"/>\n";
    o << "<text x=\"" << num(x + 26) << "\" y=\"" << num(y) << "\" font-size=\"10\">" << svg_escape(e.first) << "</text>\n";
    y += 15;
  }
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

void SvgPlot::save(const std::string& path) const { write_file_atomic(path, str()); }

}  // namespace tpkit
