#include "tpkit/geometry/reproj_eval.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "tpkit/geometry/camera_recovery.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/svg_plot.hpp"
#include "tpkit/geometry/triangulate.hpp"

namespace tpkit {

ReprojectionFrame reprojection_frame(const TrifocalTensor& T, const Eigen::MatrixXd& norm_xy) {
  ReprojectionFrame f;
  f.H = isotropic_normalization(norm_xy, true);
  f.scale = f.H[0](0, 0);
  TrifocalTensor Tn = unit_trifocal(transform_trifocal(T, f.H[0], f.H[1], f.H[2]));
  f.P = cameras_from_trifocal(Tn);
  f.P_pixels = denormalize_cameras(f.P, f.H);
  return f;
}

ReprojectionResult evaluate_reprojection(const ReprojectionFrame& f, const Eigen::MatrixXd& xy) {
  if (xy.cols() != 6) throw InputError("reprojection needs tracks with three views");
  ReprojectionResult res;
  const Eigen::Index n = xy.rows();
  res.residual.resize(n, 6);
  res.track_rms.resize(n);
  res.X.resize(n, 4);
  const Eigen::MatrixXd xn = apply_normalization(xy, f.H);
  for (Eigen::Index r = 0; r < n; ++r) {
    if (!xy.row(r).allFinite()) throw InputError("track record " + std::to_string(r + 1) + " is not finite");
    Eigen::Matrix<double, 1, 6> p = xn.row(r);
    Eigen::Vector4d X = triangulate_dlt(f.P, p);
    Eigen::Matrix<double, 1, 6> d;
    try {
      d = reprojection_residual(f.P, X, p) / f.scale;
    } catch (const NumericalError& e) {
      throw NumericalError("track record " + std::to_string(r + 1) + ": " + e.what());
    }
    res.residual.row(r) = d;
    res.track_rms(r) = std::sqrt(d.squaredNorm() / 3.0);
    res.X.row(r) = X.transpose();
  }
  res.stats = reprojection_stats(res.residual);
  return res;
}

ReprojectionStats reprojection_stats(const Eigen::MatrixXd& R) {
  ReprojectionStats s;
  s.n = static_cast<long>(R.rows());
  if (s.n == 0) return s;
  std::vector<double> len;
  len.reserve(3 * s.n);
  double total = 0;
  for (int v = 0; v < 3; ++v) {
    double sv = 0;
    for (Eigen::Index r = 0; r < R.rows(); ++r) {
      double l2 = R(r, 2 * v) * R(r, 2 * v) + R(r, 2 * v + 1) * R(r, 2 * v + 1);
      sv += l2;
      len.push_back(std::sqrt(l2));
    }
    s.rmse_view[v] = std::sqrt(sv / s.n);
    total += sv;
  }
  s.rmse = std::sqrt(total / (3.0 * s.n));
  s.max = *std::max_element(len.begin(), len.end());
  std::nth_element(len.begin(), len.begin() + len.size() / 2, len.end());
  double hi = len[len.size() / 2];
  if (len.size() % 2 == 0) {
    double lo = *std::max_element(len.begin(), len.begin() + len.size() / 2);
    s.median = 0.5 * (lo + hi);
  } else {
    s.median = hi;
  }
  return s;
}

void plot_reprojection(const std::string& path, const Eigen::MatrixXd& xy, const Eigen::MatrixXd& R,
                       const Eigen::MatrixXd& cxy, const Eigen::MatrixXd& cR, const std::string& title) {
  const double pw = 330, ph = 330, gap = 60;
  SvgPlot plot(4 * pw + 5 * gap, ph + 2 * gap + 40, title);
  // exaggeration: the 95th percentile residual drawn as 4% of the image extent
  std::vector<double> len;
  for (const auto* M : {&R, &cR})
    for (Eigen::Index r = 0; r < M->rows(); ++r)
      for (int v = 0; v < 3; ++v) len.push_back(std::hypot((*M)(r, 2 * v), (*M)(r, 2 * v + 1)));
  std::vector<double> sorted = len;
  std::sort(sorted.begin(), sorted.end());
  double p95 = sorted.empty() ? 1.0 : sorted[std::min(sorted.size() - 1, static_cast<size_t>(0.95 * sorted.size()))];
  if (!(p95 > 0)) p95 = 1.0;
  for (int v = 0; v < 3; ++v) {
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    for (const auto* M : {&xy, &cxy})
      for (Eigen::Index r = 0; r < M->rows(); ++r) {
        xmin = std::min(xmin, (*M)(r, 2 * v));
        xmax = std::max(xmax, (*M)(r, 2 * v));
        ymin = std::min(ymin, (*M)(r, 2 * v + 1));
        ymax = std::max(ymax, (*M)(r, 2 * v + 1));
      }
    if (!(xmax > xmin)) xmax = xmin + 1;
    if (!(ymax > ymin)) ymax = ymin + 1;
    double ext = std::max(xmax - xmin, ymax - ymin);
    double m = 0.06 * ext;
    double ex = 0.04 * ext / p95;  // exaggeration factor
    SvgPlot::PanelSpec spec{gap + v * (pw + gap), gap, pw, ph, xmin - m, xmax + m, ymin - m, ymax + m, true, true,
                            "view " + std::to_string(v + 1), "x (px)", "y (px)"};
    int p = plot.panel(spec);
    for (Eigen::Index r = 0; r < xy.rows(); ++r)
      plot.arrow(p, xy(r, 2 * v), xy(r, 2 * v + 1), ex * R(r, 2 * v), ex * R(r, 2 * v + 1), "#1f77b4", 0.8);
    for (Eigen::Index r = 0; r < cxy.rows(); ++r)
      plot.arrow(p, cxy(r, 2 * v), cxy(r, 2 * v + 1), ex * cR(r, 2 * v), ex * cR(r, 2 * v + 1), "#d62728", 0.8);
    // scale bar: p95 pixels
    double bx = xmin, by = ymax + 0.5 * m;
    plot.segment(p, bx, by, bx + ex * p95, by, "black", 2.0);
    std::ostringstream lab;
    lab.precision(3);
    lab << p95 << " px (x" << ex << ")";
    plot.text(p, bx + ex * p95 + 0.01 * ext, by, lab.str(), 10);
  }
  // histogram of 2-D residual lengths
  double top = sorted.empty() ? 1.0 : sorted.back();
  if (!(top > 0)) top = 1.0;
  const int bins = 30;
  std::vector<double> edges(bins + 1), counts(bins, 0.0), ccounts(bins, 0.0);
  for (int b = 0; b <= bins; ++b) edges[b] = top * b / bins;
  auto fill = [&](const Eigen::MatrixXd& M, std::vector<double>& c) {
    for (Eigen::Index r = 0; r < M.rows(); ++r)
      for (int v = 0; v < 3; ++v) {
        int b = static_cast<int>(std::hypot(M(r, 2 * v), M(r, 2 * v + 1)) / top * bins);
        c[std::min(b, bins - 1)] += 1;
      }
  };
  fill(R, counts);
  fill(cR, ccounts);
  double cmax = 1;
  for (int b = 0; b < bins; ++b) cmax = std::max(cmax, std::max(counts[b], ccounts[b]));
  SvgPlot::PanelSpec hs{gap + 3 * (pw + gap), gap, pw, ph, 0, top, 0, cmax * 1.05, false, false,
                        "residual length", "|r| (px)", "count"};
  int h = plot.panel(hs);
  plot.bars(h, edges, counts, "#1f77b4");
  std::vector<std::pair<std::string, std::string>> leg = {{"fit tracks", "#1f77b4"}};
  if (cR.rows() > 0) {
    std::vector<double> cx, cy;
    for (int b = 0; b < bins; ++b) {
      cx.push_back(0.5 * (edges[b] + edges[b + 1]));
      cy.push_back(ccounts[b]);
    }
    plot.polyline(h, cx, cy, "#d62728", 1.5);
    leg.push_back({"check tracks", "#d62728"});
  }
  plot.legend(h, leg);
  plot.save(path);
}

}  // namespace tpkit
