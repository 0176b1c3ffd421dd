#include "tpkit/geometry/reproj_eval.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "tpkit/geometry/camera_recovery.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/residual_field.hpp"
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
                       const Eigen::MatrixXd& cxy, const Eigen::MatrixXd& cR, const std::string& title,
                       const std::vector<ImageRef>& images) {
  // rows: the fit set, then the check set (if any); columns: views 1-3, a colour bar, the histogram
  const bool check = cR.rows() > 0;
  const int rows = check ? 2 : 1;
  std::vector<ResidualView> views;
  for (int set = 0; set < rows; ++set) {
    const Eigen::MatrixXd& P = set == 0 ? xy : cxy;
    const Eigen::MatrixXd& D = set == 0 ? R : cR;
    for (int v = 0; v < 3; ++v) {
      ResidualView rv;
      rv.title = std::string(set == 0 ? (check ? "fit tracks" : "tracks") : "check tracks") + ", view " + std::to_string(v + 1);
      if (v < static_cast<int>(images.size())) rv.width = images[v].width, rv.height = images[v].height;
      for (Eigen::Index r = 0; r < P.rows(); ++r) {
        rv.x.push_back(P(r, 2 * v)), rv.y.push_back(P(r, 2 * v + 1));
        rv.dx.push_back(D(r, 2 * v)), rv.dy.push_back(D(r, 2 * v + 1));
      }
      views.push_back(std::move(rv));
    }
  }
  // the panels of both sets share one extent per view (the check points may reach further)
  std::vector<std::array<double, 4>> ext(3, {1e300, 1e300, -1e300, -1e300});
  for (size_t k = 0; k < views.size(); ++k) {
    double x0, y0, x1, y1;
    view_extent(views[k], x0, y0, x1, y1);
    auto& e = ext[k % 3];
    e = {std::min(e[0], x0), std::min(e[1], y0), std::max(e[2], x1), std::max(e[3], y1)};
  }
  for (size_t k = 0; k < views.size(); ++k)
    if (!(views[k].width > 0)) {  // no image size: the union of the points' extents as the frame
      views[k].width = ext[k % 3][2] + 0.5;
      views[k].height = ext[k % 3][3] + 0.5;
    }
  std::vector<HistogramSet> hist(1);
  hist[0] = {check ? "fit" : "tracks", "#4c78a8", {}};
  for (size_t k = 0; k < 3; ++k)
    for (size_t i = 0; i < views[k].dx.size(); ++i) hist[0].length.push_back(std::hypot(views[k].dx[i], views[k].dy[i]));
  if (check) {
    hist.push_back({"check", "#e45756", {}});
    for (size_t k = 3; k < 6; ++k)
      for (size_t i = 0; i < views[k].dx.size(); ++i) hist[1].length.push_back(std::hypot(views[k].dx[i], views[k].dy[i]));
  }
  SvgPlot plot = residual_figure(views, 3, hist, title);
  plot.save(path);
}

}  // namespace tpkit
