// The plotting module (issue 27): nice and log ticks, viridis, arrows cut at the panel edge and every
// mark inside its panel, log-y bars, residual summaries against hand values, one exaggeration shared by
// every view of a figure.
#include <gtest/gtest.h>

#include <cmath>

#include "tpkit/core/coverage_plot.hpp"
#include "tpkit/core/residual_field.hpp"
#include "tpkit/core/svg_plot.hpp"

using namespace tpkit;

TEST(SvgPlot, Ticks) {
  const std::vector<double> want = {0, 0.2, 0.4, 0.6, 0.8, 1.0}, got = SvgPlot::ticks(0, 1, 5);
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-12);
  EXPECT_EQ(SvgPlot::log_ticks(1e-4, 1), (std::vector<double>{1e-4, 1e-3, 1e-2, 1e-1, 1}));
  EXPECT_EQ(SvgPlot::log_ticks(0.01, 1), (std::vector<double>{0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1}));
  EXPECT_EQ(SvgPlot::viridis(0), "#440154");
  EXPECT_EQ(SvgPlot::viridis(1), "#fde725");
  EXPECT_EQ(SvgPlot::viridis(-3), "#440154");
}

TEST(SvgPlot, ArrowsCutAtThePanelEdgeAndMarksInside) {
  SvgPlot plot(400, 300, "t");
  SvgPlot::PanelSpec s = SvgPlot::spec(50, 50, 200, 200, 0, 100, 0, 100, "p", "x", "y");
  s.y_down = true;
  int p = plot.panel(s);
  EXPECT_TRUE(plot.arrow(p, 50, 50, 10, 10, "black"));
  EXPECT_FALSE(plot.arrow(p, 50, 50, 500, -300, "black"));  // cut: its end ringed, inside
  EXPECT_FALSE(plot.arrow(p, 150, 50, 1, 1, "black"));      // starts outside: nothing drawn
  plot.points(p, {10, 200}, {10, 10}, "red", 2, "cross");
  EXPECT_EQ(plot.points_outside(), 1);
  plot.cell(p, -50, -50, 20, 20, "#ccc");
  plot.polyline(p, {0, 50, 300}, {0, 50, -100}, "blue");
  EXPECT_TRUE(plot.marks_inside());
  EXPECT_NE(plot.str().find("class=\"cut\""), std::string::npos);
  EXPECT_NE(plot.str().find("clip-path=\"url(#clip"), std::string::npos);
  SvgPlot other(10, 10);
  other.panel(SvgPlot::spec(0, 0, 10, 10, 0, 1, 0, 1, "", "", ""));
  const std::string a = plot.str(), b = other.str();
  const auto id = [](const std::string& s) { auto i = s.find("<clipPath id=\""); return s.substr(i, s.find('"', i + 15) - i); };
  EXPECT_NE(id(a), id(b));  // two plots inlined in one page do not share clip ids
}

TEST(SvgPlot, LogBarsInside) {
  SvgPlot plot(400, 300);
  SvgPlot::PanelSpec s = SvgPlot::spec(50, 50, 200, 200, 0, 1, 1e-3, 1, "", "", "");
  s.log_y = true;
  int p = plot.panel(s);
  plot.bars(p, {0, 0.5, 1}, {0.9, 1e-5}, "blue");  // the second bar is below the axis: not drawn
  ASSERT_EQ(plot.marks().size(), 1u);
  const auto& m = plot.marks()[0];
  EXPECT_NEAR(m.y1, 250, 1e-9);                                  // from the panel's bottom
  EXPECT_NEAR(m.y0, 250 - 200 * (std::log10(0.9) + 3) / 3, 1e-9);  // to log10(0.9) on 3 decades
  EXPECT_TRUE(plot.marks_inside());
}

TEST(ResidualField, SummaryAgainstHandValues) {
  // lengths 3, 4, 5, 0, 12 (3-4-5 and 5-12-13 triangles)
  ResidualSummary s = summarize_residuals({3, 0, 3, 0, 5}, {0, 4, 4, 0, 12});
  EXPECT_EQ(s.n, 5);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt((9 + 16 + 25 + 0 + 169) / 5.0));
  EXPECT_DOUBLE_EQ(s.median, 4);
  EXPECT_DOUBLE_EQ(s.p90, 13);
  EXPECT_EQ(format_rmse(0.100345729), "0.1003");
  EXPECT_EQ(residual_summary_text(s).find("RMSE " + format_rmse(s.rmse) + " px "), 0u);
}

TEST(ResidualField, OneExaggerationForEveryViewAndMarksInside) {
  // two 1000 x 1000 views, a smooth field (0.1 px at most) on a grid of points, the second 3 times larger
  std::vector<ResidualView> v(2);
  for (int k = 0; k < 2; ++k) {
    v[k].width = v[k].height = 1000;
    for (int i = 0; i < 60; ++i)
      for (int j = 0; j < 60; ++j) {
        double x = 8 + 16.5 * i, y = 8 + 16.5 * j;
        v[k].x.push_back(x), v[k].y.push_back(y);
        v[k].dx.push_back((k + 1) * 0.05 * x / 1000), v[k].dy.push_back(-(k + 1) * 0.03);
      }
  }
  v[1].dx.back() = 40;  // one gross outlier: beyond p99, shortened or cut, never out of the panel
  v.push_back(ResidualView{});  // a hole in the figure's grid changes nothing
  FieldScale fs = field_scale(v);
  v.pop_back();
  // cells 62.5 px; the 95th percentile of the cell means (the larger view's) spans 90% of a cell
  EXPECT_GT(fs.exaggeration, 0.9 * 62.5 / 0.2);
  EXPECT_LT(fs.exaggeration, 0.9 * 62.5 / 0.09);
  SvgPlot plot(900, 500);
  for (int k = 0; k < 2; ++k) {
    SvgPlot::PanelSpec s = SvgPlot::spec(50 + 420 * k, 60, 380, 380, -0.5, 999.5, -0.5, 999.5, "", "", "");
    s.y_down = s.equal_aspect = true;
    draw_residual_field(plot, plot.panel(s), v[k], fs);
  }
  field_legend(plot, 50, 490, fs);
  EXPECT_TRUE(plot.marks_inside());
  const std::string svg = plot.str();
  EXPECT_EQ(svg.find(exaggeration_text(fs)), svg.rfind(exaggeration_text(fs)));  // stated once
}

TEST(Coverage, EmptyCellsCountedAndMarksInside) {
  // points on the left half of a 1000 x 500 image only: 16 x 8 cells, the right 8 columns empty
  CoverageView v;
  v.title = "left half";
  v.width = 1000, v.height = 500;
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 25; ++j) v.x.push_back(5 + 10 * i), v.y.push_back(5 + 20 * j);
  SvgPlot plot = coverage_figure({v}, "t");
  EXPECT_TRUE(plot.marks_inside());
  const std::string svg = plot.str();
  EXPECT_NE(svg.find("1250 points; 64 of 128 cells without any (50%); no thumbnail: image not found"), std::string::npos);
}
