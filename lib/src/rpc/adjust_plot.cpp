#include "tpkit/rpc/adjust_plot.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "tpkit/core/svg_plot.hpp"
#include "tpkit/core/text_table.hpp"

namespace tpkit {

namespace fs = std::filesystem;

void plot_rpc_residuals(const std::string& path, const std::vector<AdjustImage>& images, const AdjustResult& r,
                        const std::string& title) {
  const int n = static_cast<int>(images.size());
  const int cols = std::min(n, 4), rows_of_images = (n + cols - 1) / cols;
  const double pw = 300, ph = 300, gap = 60;
  SvgPlot plot(cols * (pw + gap) + gap, rows_of_images * (ph + gap) + gap + 40, title);
  // one exaggeration for the whole figure: the 90th percentile of the residuals before -> 4% of the width
  std::vector<double> len;
  for (const auto& e : r.res_before) len.push_back(e.norm());
  std::sort(len.begin(), len.end());
  double p90 = len.empty() ? 1 : std::max(len[len.size() * 9 / 10], 1e-3);
  long wmax = 1;
  for (const auto& im : images) wmax = std::max(wmax, std::max(im.width, im.height));
  const double k = 0.04 * wmax / p90;
  for (int i = 0; i < n; ++i) {
    SvgPlot::PanelSpec s;
    s.left = gap + (i % cols) * (pw + gap);
    s.top = gap + 20 + (i / cols) * (ph + gap);
    s.width = pw;
    s.height = ph;
    s.xmin = -0.5;
    s.xmax = images[i].width - 0.5;
    s.ymin = -0.5;
    s.ymax = images[i].height - 0.5;
    s.y_down = true;
    s.equal_aspect = true;
    s.title = fs::path(images[i].path).filename().string() + (images[i].fixed ? " (fixed)" : "") + ": before " +
              format_number(std::round(residual_rms(r, false, i) * 1000) / 1000) + " px, after " +
              format_number(std::round(residual_rms(r, true, i) * 1000) / 1000) + " px";
    s.xlabel = "x (px)";
    s.ylabel = "y (px)";
    int p = plot.panel(s);
    // at most ~1500 arrows per panel (every m-th observation)
    long count = std::count(r.obs_image.begin(), r.obs_image.end(), i);
    long step = std::max(1L, count / 1500), seen = 0;
    for (size_t o = 0; o < r.obs_image.size(); ++o) {
      if (r.obs_image[o] != i || (seen++ % step) != 0) continue;
      const auto& q = r.obs_xy[o];
      plot.arrow(p, q[0], q[1], k * r.res_before[o][0], k * r.res_before[o][1], "#d62728", 0.6);
      plot.arrow(p, q[0], q[1], k * r.res_after[o][0], k * r.res_after[o][1], "#1f77b4", 0.8);
    }
    if (i == 0) {
      plot.segment(p, 0.05 * images[i].width, 0.95 * images[i].height, 0.05 * images[i].width + k * p90,
                   0.95 * images[i].height, "black", 2);
      plot.text(p, 0.05 * images[i].width, 0.92 * images[i].height, format_number(std::round(p90 * 1000) / 1000) + " px", 10);
      plot.legend(p, {{"before (zero bias)", "#d62728"}, {"after", "#1f77b4"}});
    }
  }
  plot.save(path);
}

}  // namespace tpkit
