// Small SVG plots for the tools' figures (reproj-eval residual maps and histograms, cluster-homog cost
// curves and cluster pictures): panels with axes, ticks and labels; lines, points, arrows, bars, text.
// Data coordinates are mapped into each panel; `y_down` panels put y = ymin at the top (image rows).
#pragma once
#include <string>
#include <vector>

namespace tpkit {

class SvgPlot {
 public:
  SvgPlot(double width, double height, std::string title = "");

  struct PanelSpec {
    double left, top, width, height;       // placement on the page, in SVG units
    double xmin, xmax, ymin, ymax;          // data ranges
    bool y_down = false;                    // image convention (row 0 at the top)
    bool equal_aspect = false;              // same scale on both axes (ranges are widened to fit)
    std::string title, xlabel, ylabel;
  };
  // Returns the panel's index.
  int panel(PanelSpec spec);

  void polyline(int p, const std::vector<double>& x, const std::vector<double>& y, const std::string& color,
                double width = 1.5);
  void points(int p, const std::vector<double>& x, const std::vector<double>& y, const std::string& color,
              double radius = 2.0, const std::string& shape = "circle");  // circle | cross | square
  // Arrow from (x, y) by (dx, dy) in data units.
  void arrow(int p, double x, double y, double dx, double dy, const std::string& color, double width = 1.0);
  // Histogram bars: counts[i] between edges[i] and edges[i + 1].
  void bars(int p, const std::vector<double>& edges, const std::vector<double>& counts, const std::string& color);
  // A segment in data units (e.g. a scale bar).
  void segment(int p, double x0, double y0, double x1, double y1, const std::string& color, double width = 1.5);
  void text(int p, double x, double y, const std::string& s, double size = 11, const std::string& anchor = "start");
  // Text at page coordinates.
  void page_text(double x, double y, const std::string& s, double size = 12, const std::string& anchor = "start");
  void legend(int p, const std::vector<std::pair<std::string, std::string>>& entries);  // (label, color)

  std::string str() const;
  // Atomic write (atomic_output.hpp).
  void save(const std::string& path) const;

  // "Nice" axis ticks covering [lo, hi].
  static std::vector<double> ticks(double lo, double hi, int target = 6);

 private:
  struct Panel {
    PanelSpec s;
    double sx, sy;  // data-to-page scales
  };
  double px(const Panel& p, double x) const;
  double py(const Panel& p, double y) const;
  double width_, height_;
  std::vector<Panel> panels_;
  std::string body_;
};

// Escapes &, <, > and quotes for SVG text.
std::string svg_escape(const std::string& s);

}  // namespace tpkit
