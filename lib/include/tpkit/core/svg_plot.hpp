// Small SVG plots for the tools' figures (reproj-eval and rpc-adjust residual fields and histograms,
// cluster-homog cost curves and cluster pictures): panels with axes, nice ticks (linear or log y) and
// labels; lines, points, arrows, bars, cells, text; colour bars (viridis); legends whose symbols are the
// marks drawn. Data coordinates are mapped into each panel; `y_down` panels put y = ymin at the top
// (image rows). Every mark is kept inside its panel: arrows are cut at the panel edge and their cut end
// marked (an open circle), points outside are left out and counted, bars and lines are clamped; the page
// box of every mark is recorded (marks()) so tests can check it. Titles, notes, labels and legends sit
// outside the panels' data area.
#pragma once
#include <string>
#include <vector>

namespace tpkit {

class SvgPlot {
 public:
  SvgPlot(double width, double height, std::string title = "");

  struct PanelSpec {
    double left = 0, top = 0, width = 1, height = 1;  // placement on the page, in SVG units
    double xmin = 0, xmax = 1, ymin = 0, ymax = 1;    // data ranges
    bool y_down = false;                    // image convention (row 0 at the top)
    bool equal_aspect = false;              // same scale on both axes (ranges are widened to fit)
    std::string title, xlabel, ylabel;
    bool log_y = false;                     // log10 y axis (ymin > 0; values below ymin drawn at ymin)
    std::string note;                       // one line under the title, above the panel (e.g. RMSE)
  };
  // A legend's symbol: the mark it names, drawn as that mark.
  enum class Mark { dot, cross, ring, line, arrow, box, frame };  // box filled, frame outlined
  struct LegendEntry {
    std::string label, color;
    Mark mark = Mark::line;
  };
  struct Box {
    int panel;  // -1: page furniture (colour bar)
    double x0, y0, x1, y1;
  };
  // A spec with the given placement, ranges and words (y up, free aspect, linear).
  static PanelSpec spec(double left, double top, double width, double height, double xmin, double xmax, double ymin,
                        double ymax, std::string title, std::string xlabel, std::string ylabel) {
    PanelSpec s;
    s.left = left, s.top = top, s.width = width, s.height = height;
    s.xmin = xmin, s.xmax = xmax, s.ymin = ymin, s.ymax = ymax;
    s.title = std::move(title), s.xlabel = std::move(xlabel), s.ylabel = std::move(ylabel);
    return s;
  }
  // Returns the panel's index.
  int panel(PanelSpec spec);

  void polyline(int p, const std::vector<double>& x, const std::vector<double>& y, const std::string& color,
                double width = 1.5);
  void points(int p, const std::vector<double>& x, const std::vector<double>& y, const std::string& color,
              double radius = 2.0, const std::string& shape = "circle");  // circle | cross | ring | square
  // Arrow from (x, y) by (dx, dy) in data units, cut at the panel edge (the cut end marked by an open
  // circle, no head). Returns false when it had to be cut (or starts outside: then nothing is drawn).
  bool arrow(int p, double x, double y, double dx, double dy, const std::string& color, double width = 1.0);
  // A filled rectangle in data units (e.g. a grid cell), clamped to the panel.
  void cell(int p, double x0, double y0, double x1, double y1, const std::string& fill, double opacity = 1.0);
  // Histogram bars: counts[i] between edges[i] and edges[i + 1].
  void bars(int p, const std::vector<double>& edges, const std::vector<double>& counts, const std::string& color);
  // A segment in data units (e.g. a scale bar).
  void segment(int p, double x0, double y0, double x1, double y1, const std::string& color, double width = 1.5);
  void text(int p, double x, double y, const std::string& s, double size = 11, const std::string& anchor = "start");
  // Text at page coordinates.
  void page_text(double x, double y, const std::string& s, double size = 12, const std::string& anchor = "start");
  // Legend in one row below panel p's x label (outside the data area), from its left edge.
  void legend(int p, const std::vector<LegendEntry>& entries);
  // Legend at page coordinates (first entry's symbol at x, baseline y), one row.
  void legend_at(double x, double y, const std::vector<LegendEntry>& entries);
  // A vertical colour bar (viridis from vmin at the bottom to vmax at the top) at page coordinates, with
  // ticks and a label on its right.
  void colorbar(double left, double top, double width, double height, double vmin, double vmax,
                const std::string& label);
  // Points that points() left out because they fell outside their panel.
  long points_outside() const { return points_outside_; }
  // The page box of every mark drawn in a panel, and of every panel (for tests: all inside).
  const std::vector<Box>& marks() const { return marks_; }
  Box panel_box(int p) const;
  // True when every mark's box lies inside its panel's box (within `tol` page units).
  bool marks_inside(double tol = 0.01) const;

  std::string str() const;
  // The <svg> element alone (no XML declaration), for inlining in HTML.
  std::string inline_svg() const;
  // Atomic write (atomic_output.hpp).
  void save(const std::string& path) const;

  // "Nice" axis ticks covering [lo, hi]; log_ticks: the powers of ten (and 2, 5 times them when few).
  static std::vector<double> ticks(double lo, double hi, int target = 6);
  static std::vector<double> log_ticks(double lo, double hi);
  // Viridis colour at t in [0, 1] (clamped), as #rrggbb.
  static std::string viridis(double t);

 private:
  struct Panel {
    PanelSpec s;
    double sx, sy;  // data-to-page scales
  };
  double px(const Panel& p, double x) const;
  double py(const Panel& p, double y) const;
  void record(int p, double x0, double y0, double x1, double y1);
  double width_, height_;
  int id_;  // this plot's number in the process (unique clip-path ids)
  std::vector<Panel> panels_;
  std::vector<Box> marks_;
  long points_outside_ = 0;
  std::string body_;
};

// Escapes &, <, > and quotes for SVG text.
std::string svg_escape(const std::string& s);

}  // namespace tpkit
