// See cluster_scan.hpp.
#include "tpkit/cluster/cluster_scan.hpp"

#include <algorithm>
#include <cmath>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/svg_plot.hpp"

namespace tpkit {

void check_scan(const std::string& param, double lo, double hi, int steps) {
  if (steps < 2 || steps > kMaxScanSteps)
    throw UsageError("--steps must be between 2 and " + std::to_string(kMaxScanSteps) + ", got " + std::to_string(steps));
  if (!(lo < hi) || !std::isfinite(lo) || !std::isfinite(hi)) throw UsageError("--range needs LO < HI, both finite");
  const bool h_entry = param.size() == 3 && param[0] == 'h' && param[1] >= '1' && param[1] <= '3' && param[2] >= '1' &&
                       param[2] <= '3';
  if (physical_param_index(param) < 0 && !h_entry)
    throw UsageError("unknown scan parameter '" + param + "' (h11 ... h33, or px1 py1 rho1 alpha1 beta1 gamma1 res1 theta1 cx1 cy1 and the same with 2)");
}

std::vector<ScanRow> scan_cost(const ClusterCost& cost, const std::string& param, const Eigen::Matrix3d& H,
                               const PhysicalParams* phys, double lo, double hi, int steps) {
  check_scan(param, lo, hi, steps);
  const int pi = physical_param_index(param);
  const int hr = pi < 0 ? param[1] - '1' : -1, hc = pi < 0 ? param[2] - '1' : -1;
  if (pi >= 0 && !phys) throw UsageError("scanning a physical parameter needs physical parameters (--param physical with --init)");
  std::vector<ScanRow> rows;
  Eigen::Matrix3d Hn = normalized_homography(H);
  auto base = phys ? phys->array() : std::array<double, kPhysicalParamCount>{};
  for (int s = 0; s < steps; ++s) {
    double v = lo + (hi - lo) * s / (steps - 1);
    Eigen::Matrix3d M;
    if (pi >= 0) {
      auto p = base;
      p[pi] = v;
      if (!physical_params_problem(PhysicalParams::from_array(p.data())).empty()) continue;
      M = physical_homography_t(p.data());
    } else {
      M = Hn;
      M(hr, hc) = v;
    }
    double c = cost(M);
    if (std::isfinite(c)) rows.push_back({v, c});
  }
  return rows;
}

void save_scan(const std::string& path, const std::vector<ScanRow>& rows, const std::string& param,
               const std::vector<ImageRef>& images, Meta meta) {
  meta_set(meta, "parameter", param);
  AtomicOutput out(path);
  write_header(out.stream(), "scan", 1, images, meta, {"value", "cost"});
  for (const auto& r : rows) write_record(out.stream(), {r.value, r.cost});
  out.commit();
}

namespace {
// The scanned parameter with its unit (physical_homography.hpp; h11..h33 are H's entries, h33 = 1).
std::string param_axis_label(const std::string& param) {
  const std::string base = param.substr(0, param.find_first_of("0123456789"));
  if (base == "px" || base == "py" || base == "rho") return param + " (m)";
  if (base == "alpha" || base == "beta" || base == "gamma" || base == "theta") return param + " (rad)";
  if (base == "res") return param + " (m per pixel)";
  if (base == "cx" || base == "cy") return param + " (pixels)";
  return param + " (homography entry, h33 = 1)";
}
}  // namespace

void plot_scan(const std::string& path, const std::vector<ScanRow>& rows, const std::string& param,
               const std::string& title) {
  if (rows.empty()) throw NumericalError("nothing to plot: every scanned value gave a singular homography");
  double xmin = rows.front().value, xmax = rows.back().value, ymax = 0;
  for (const auto& r : rows) ymax = std::max(ymax, r.cost);
  if (!(ymax > 0)) ymax = 1;
  SvgPlot plot(720, 460, title);
  int p = plot.panel(SvgPlot::spec(70, 50, 620, 350, xmin, xmax, 0, ymax * 1.05, "", param_axis_label(param),
                                   "cost (pixels)"));
  std::vector<double> x, y;
  for (const auto& r : rows) x.push_back(r.value), y.push_back(r.cost);
  plot.polyline(p, x, y, "#1f5fa8", 1.5);
  plot.save(path);
}

void save_pairs(const std::string& path, const ClusterCost& cost, const std::vector<MutualPair>& pairs,
                const std::vector<ImageRef>& images, const Meta& meta) {
  AtomicOutput out(path);
  write_header(out.stream(), "pairs", 1, images, meta, {"x1", "y1", "x2", "y2", "d"});
  for (const auto& p : pairs)
    write_record(out.stream(), {cost.a()(p.ia, 0), cost.a()(p.ia, 1), cost.b()(p.ib, 0), cost.b()(p.ib, 1), p.d});
  out.commit();
}

void plot_clusters(const std::string& path, const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B,
                   const Eigen::Matrix3d& H_before, double cost_before, const Eigen::Matrix3d& H_after,
                   double cost_after) {
  auto carry = [&](const Eigen::Matrix3d& H, std::vector<double>& x, std::vector<double>& y) {
    for (Eigen::Index i = 0; i < A.rows(); ++i) {
      Eigen::Vector3d q = H * Eigen::Vector3d(A(i, 0), A(i, 1), 1.0);
      if (std::fabs(q.z()) < 1e-12) continue;
      x.push_back(q.x() / q.z());
      y.push_back(q.y() / q.z());
    }
  };
  std::vector<double> bx(B.rows()), by(B.rows()), x0, y0, x1, y1;
  for (Eigen::Index i = 0; i < B.rows(); ++i) bx[i] = B(i, 0), by[i] = B(i, 1);
  carry(H_before, x0, y0);
  carry(H_after, x1, y1);
  // both panels share B's extent (widened by 25%) so that a badly wrong start stays readable
  double xmin = *std::min_element(bx.begin(), bx.end()), xmax = *std::max_element(bx.begin(), bx.end());
  double ymin = *std::min_element(by.begin(), by.end()), ymax = *std::max_element(by.begin(), by.end());
  double mx = 0.25 * (xmax - xmin) + 1, my = 0.25 * (ymax - ymin) + 1;
  SvgPlot svg(1000, 560, "point clusters before and after (Navy et al. figure 6), image-2 pixels");
  auto fmt = [](double c) {
    char b[64];
    std::snprintf(b, sizeof b, "%.3g px", c);
    return std::string(b);
  };
  for (int k = 0; k < 2; ++k) {
    SvgPlot::PanelSpec ps = SvgPlot::spec(70.0 + k * 480, 60, 400, 400, xmin - mx, xmax + mx, ymin - my, ymax + my, "", "", "");
    ps.y_down = ps.equal_aspect = true;
    ps.title = (k == 0 ? "start, cost " + fmt(cost_before) : "result, cost " + fmt(cost_after));
    ps.xlabel = "x (px)";
    ps.ylabel = "y (px)";
    int p = svg.panel(ps);
    svg.points(p, bx, by, "#1f77b4", 3.0, "circle");
    svg.points(p, k == 0 ? x0 : x1, k == 0 ? y0 : y1, "#d62728", 3.5, "cross");
    svg.legend(p, {{"cluster B", "#1f77b4", SvgPlot::Mark::dot}, {"h(cluster A)", "#d62728", SvgPlot::Mark::cross}});
  }
  svg.save(path);
}

}  // namespace tpkit
