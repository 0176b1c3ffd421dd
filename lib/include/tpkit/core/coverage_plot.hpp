// Coverage figure: where an image has tie points and where it has none (clouds, water, shadow, the edges
// of the overlap). Per image, the points counted in a grid of cells over a greyscale thumbnail of the
// image (block means, contrast stretched 2-98%), the cells with points tinted by their count (viridis,
// one colour bar per figure), the cells without any outlined in red. Self-contained SVG (the thumbnail
// is drawn as grey cells, no embedded raster). Positions are pixels, x = column, y = row.
#pragma once
#include <string>
#include <vector>

#include "tpkit/core/svg_plot.hpp"

namespace tpkit {

struct CoverageView {
  std::string title;
  std::string image;           // path of the image for the thumbnail ("" or unreadable: none, said)
  double width = 0, height = 0;  // image size (px); 0: the points' extent
  std::vector<double> x, y;
};

// The figure of several views in a row of panels; `cells` along the longer side.
SvgPlot coverage_figure(const std::vector<CoverageView>& views, const std::string& title, int cells = 16);

}  // namespace tpkit
