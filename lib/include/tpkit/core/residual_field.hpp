// Residual fields: the picture of image-space residuals a photogrammetrist reads at a glance. Per view, the
// count-weighted mean residual vector in a grid of cells over the image, coloured by its magnitude
// (viridis, one colour bar), drawn with ONE exaggeration shared by every panel of a figure; cells with
// few points greyed and their individual vectors drawn instead (thin, grey); vectors longer than the
// figure's clip percentile shortened to it and marked; RMSE, median and p90 printed above each panel.
// Conventions: positions are pixels, x = column, y = row, (0, 0) the centre of the top-left pixel;
// residuals are pixels (any sign convention: the caller's, stated in its legend).
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "tpkit/core/svg_plot.hpp"

namespace tpkit {

struct ResidualView {
  std::string title;
  double width = 0, height = 0;  // image extent (px); 0: the points' extent
  std::vector<double> x, y, dx, dy;
};

struct ResidualSummary {
  long n = 0;
  double rmse = 0, median = 0, p90 = 0;  // of the 2-D residual lengths, px
};
ResidualSummary summarize_residuals(const std::vector<double>& dx, const std::vector<double>& dy);
// "RMSE 0.1003 px · median 0.0702 · p90 0.1512 · n 7293" (4 significant digits, format_rmse).
std::string residual_summary_text(const ResidualSummary& s);
// A length in px to 4 significant digits, as figures print it (tests compare a file's summary line).
std::string format_rmse(double v);

struct ResidualGrid {
  int nx = 0, ny = 0;
  double cw = 1, ch = 1;  // cell size (px)
  std::vector<double> mx, my;  // mean residual per cell (row-major, ny rows of nx)
  std::vector<long> count;
};
ResidualGrid residual_grid(const ResidualView& v, int cells);

// One scale for a whole figure: `exaggeration` (page length = exaggeration x residual, in data units),
// `vmax` the colour bar's top (px), `clip` the length beyond which single vectors are shortened (px).
struct FieldScale {
  double exaggeration = 1, vmax = 1, clip = 1, key = 1;  // key: the legend's key arrow (px)
  int cells = 16;
  long min_count = 5;  // cells with fewer points are greyed (their vectors drawn one by one)
  double clip_percentile = 99;
};
FieldScale field_scale(const std::vector<ResidualView>& views, int cells = 16, long min_count = 5);

// The panel's data extent for a view (the image extent, else the points').
void view_extent(const ResidualView& v, double& x0, double& y0, double& x1, double& y1);
// Draws v's field in panel p (made with view_extent, y_down, equal_aspect).
void draw_residual_field(SvgPlot& plot, int p, const ResidualView& v, const FieldScale& s);
// The figure's legend line (key arrow, exaggeration, grey cells, clip) and colour bar. The text states
// "vectors xE" once: the one exaggeration of the figure.
void field_legend(SvgPlot& plot, double x, double y, const FieldScale& s);
std::string exaggeration_text(const FieldScale& s);

// Histogram of residual lengths of several sets, each normalised to a fraction of its points, on a log
// axis: the first set as bars, the others as step lines, legends matching.
struct HistogramSet {
  std::string label, color;
  std::vector<double> length;
};
void draw_length_histogram(SvgPlot& plot, double left, double top, double width, double height,
                           const std::vector<HistogramSet>& sets, const std::string& title);

// A whole residual figure: the views' fields in a grid of `cols` columns (row-major, all square panels,
// one FieldScale), a colour bar right of the grid, the histogram of `hist` (if any) right of it, the
// legend at the bottom. `extra(plot, panel, k)` may draw more in view k's panel (same data units).
SvgPlot residual_figure(const std::vector<ResidualView>& views, int cols, const std::vector<HistogramSet>& hist,
                        const std::string& title,
                        const std::function<void(SvgPlot&, int, size_t, const FieldScale&)>& extra = {},
                        const std::vector<SvgPlot::LegendEntry>& more_legend = {});

}  // namespace tpkit
