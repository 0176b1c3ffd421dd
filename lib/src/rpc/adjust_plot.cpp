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
  const int cols = std::max(1, std::min(n, 4)), blocks = (n + cols - 1) / cols;
  const double pw = 300, top = 78, left = 75, hgap = 75, vgap = 85;
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
  const FieldScale fs = field_scale(views);
  const double cbar_x = left + cols * pw + (cols - 1) * hgap + 20;
  const double height = top + blocks * (2 * pw + 2 * vgap) - vgap + 95;
  SvgPlot plot(cbar_x + 110, height, title);
  for (int i = 0; i < n; ++i)
    for (int after = 0; after < 2; ++after) {
      const ResidualView& v = views[2 * i + after];
      double x0, y0, x1, y1;
      view_extent(v, x0, y0, x1, y1);
      const int row = 2 * (i / cols) + after;
      SvgPlot::PanelSpec s = SvgPlot::spec(left + (i % cols) * (pw + hgap), top + row * (pw + vgap), pw, pw, x0, x1, y0,
                                           y1, v.title, "x (px)", "y (px)");
      s.y_down = s.equal_aspect = true;
      s.note = residual_summary_text(summarize_residuals(v.dx, v.dy));
      const int p = plot.panel(s);
      draw_residual_field(plot, p, v, fs);
      if (after || i >= static_cast<int>(r.bias.size()) || r.bias[i].zero()) continue;
      const ResidualGrid g = residual_grid(v, fs.cells);
      for (int cy = 0; cy < g.ny; ++cy)
        for (int cx = 0; cx < g.nx; ++cx) {
          if (g.count[cy * g.nx + cx] < fs.min_count) continue;
          const Eigen::Vector2d c(x0 + (cx + 0.5) * g.cw, y0 + (cy + 0.5) * g.ch);
          const Eigen::Vector2d m = -r.bias[i].offset(c);
          plot.arrow(p, c[0], c[1], fs.exaggeration * m[0], fs.exaggeration * m[1], "#e4002b", 0.9);
        }
    }
  plot.colorbar(cbar_x, top, 16, pw, 0, fs.vmax, "|cell mean residual| (px)");
  field_legend(plot, left, height - 36, fs);
  plot.legend_at(left, height - 14,
                 {{"bias model fitted, drawn as -offset (the image shift it removes) from the cell centres", "#e4002b",
                   SvgPlot::Mark::arrow}});
  plot.save(path);
}

}  // namespace tpkit
