#include "tpkit/rpc/adjust_plot.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "tpkit/core/residual_field.hpp"
#include "tpkit/core/svg_plot.hpp"

namespace tpkit {

namespace fs = std::filesystem;

// Layout: images in blocks of up to 4 columns; each block two rows, before (zero bias) above after. Every
// panel shares one exaggeration and one colour scale (core/residual_field.hpp), so before and after of
// an image compare directly. Residuals are projected minus observed (px). The bias model's field is
// drawn in the "before" panels as -offset (the residual it explains), at the cells' centres, in red.
void plot_rpc_residuals(const std::string& path, const std::vector<AdjustImage>& images, const AdjustResult& r,
                        const std::string& title) {
  const int n = static_cast<int>(images.size());
  const int cols = std::max(1, std::min(n, 4));
  std::vector<ResidualView> views(2 * n);  // 2i: before, 2i+1: after
  for (int i = 0; i < n; ++i)
    for (int after = 0; after < 2; ++after) {
      ResidualView& v = views[2 * i + after];
      v.title = fs::path(images[i].path).filename().string() + (images[i].fixed ? " (fixed)" : "") +
                (after ? ", after" : ", before (zero bias)");
      v.width = static_cast<double>(images[i].width);
      v.height = static_cast<double>(images[i].height);
    }
  for (size_t o = 0; o < r.obs_image.size(); ++o)
    for (int after = 0; after < 2; ++after) {
      ResidualView& v = views[2 * r.obs_image[o] + after];
      const auto& d = after ? r.res_after[o] : r.res_before[o];
      v.x.push_back(r.obs_xy[o][0]), v.y.push_back(r.obs_xy[o][1]);
      v.dx.push_back(d[0]), v.dy.push_back(d[1]);
    }
  // before above after: a grid of `cols` columns in which image i's panels are 2 rows apart
  std::vector<ResidualView> grid;
  std::vector<int> grid_image;  // image of a "before" panel, -1 otherwise
  for (int block = 0; block * cols < n; ++block)
    for (int after = 0; after < 2; ++after)
      for (int c = 0; c < cols; ++c) {
        const int i = block * cols + c;
        grid.push_back(i < n ? views[2 * i + after] : ResidualView{});
        grid_image.push_back(i < n && !after ? i : -1);
      }
  auto bias_field = [&](SvgPlot& plot, int p, size_t k, const FieldScale& fs) {
    const int i = grid_image[k];
    if (i < 0 || i >= static_cast<int>(r.bias.size()) || r.bias[i].zero()) return;
    double x0, y0, x1, y1;
    view_extent(grid[k], x0, y0, x1, y1);
    const ResidualGrid g = residual_grid(grid[k], fs.cells);
    for (int cy = 0; cy < g.ny; ++cy)
      for (int cx = 0; cx < g.nx; ++cx) {
        if (g.count[cy * g.nx + cx] < fs.min_count) continue;
        const Eigen::Vector2d c(x0 + (cx + 0.5) * g.cw, y0 + (cy + 0.5) * g.ch);
        const Eigen::Vector2d m = -r.bias[i].offset(c);
        plot.arrow(p, c[0], c[1], fs.exaggeration * m[0], fs.exaggeration * m[1], "#e4002b", 0.9);
      }
  };
  SvgPlot plot = residual_figure(
      grid, cols, {}, title, bias_field,
      {{"bias model fitted, drawn as -offset (the image shift it removes) from the cell centres", "#e4002b",
        SvgPlot::Mark::arrow}});
  plot.save(path);
}

}  // namespace tpkit
