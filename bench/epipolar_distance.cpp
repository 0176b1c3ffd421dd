// bench_epipolar_distance: how far a pair's matches lie from the RPC epipolar curves, once an affine bias
// of each image's model is removed: the precision of tie points on real imagery, where no truth is known
// but the models' epipolar geometry is (issue 51, 52).
//
//   bench_epipolar_distance IMAGE1 IMAGE2 MATCHES... [--rpc1 MODEL] [--rpc2 MODEL] [--heights LO,HI]
//
// Conventions: image 1 is IMAGE1, the matches' x1 y1; image 2 is IMAGE2, x2 y2; tpkit pixels ((0, 0) the
// centre of the top-left pixel); heights in metres above the ellipsoid. The models are read as the tools
// read them (tag 50844, sidecars, NITF TREs) unless --rpc1/--rpc2 name a model file.
//
// For each match, d = the signed distance (pixels of image 2) from (x2, y2) to the epipolar curve of
// (x1, y1) (the curve as a polyline of 64 heights over --heights, by default the range both models are
// valid for), its sign that of the curve's left normal. An affine bias of either image's model moves the
// matches across their curves by an affine function of the position (only the across-curve part of the
// models' relative bias is observable from a pair): a plane over image 2, fitted to every record of a file
// by a Huber reweighted least squares, is removed; what remains is the match's distance. Printed per file: records, refined records (column
// `refined`, when the file has one), then RMS and median |d| of all records and of the refined ones,
// before and after the bias is removed. A matches file of another program (COLMAP through
// `tp-convert --from colmap`) is scored the same way. --dump FILE: one row per record (file, x1 y1 x2 y2,
// sigma, refined, the distance before and after the bias is removed), for error analysis.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace {
constexpr int kCurveSamples = 64;
constexpr double kHuber = 1.345;  // Huber's constant, in units of the residuals' robust scale

// The signed distance (pixels) of q (image 2) from the epipolar curve of p (image 1), its sign that of
// the curve's left normal at the closest point.
std::optional<double> across_curve(const tpkit::RpcModel& a, const tpkit::RpcModel& b, const Eigen::Vector2d& p,
                                   const Eigen::Vector2d& q, double lo, double hi) {
  const std::vector<Eigen::Vector3d> c = tpkit::epipolar_curve(a, b, p.x(), p.y(), lo, hi, kCurveSamples);
  double best = INFINITY, signed_distance = NAN;
  for (size_t k = 0; k + 1 < c.size(); ++k) {
    const Eigen::Vector2d s0 = c[k].head<2>(), s1 = c[k + 1].head<2>(), dir = s1 - s0;
    const double len2 = dir.squaredNorm();
    if (!(len2 > 0)) continue;
    const double t = std::clamp((q - s0).dot(dir) / len2, 0.0, 1.0);
    const Eigen::Vector2d foot = s0 + t * dir;
    const double dist = (q - foot).norm();
    if (dist < best) {
      best = dist;
      signed_distance = Eigen::Vector2d(-dir.y(), dir.x()).dot(q - foot) / std::sqrt(len2);
    }
  }
  if (!std::isfinite(best)) return std::nullopt;
  return signed_distance;
}

double median_abs(std::vector<double> v) {
  if (v.empty()) return NAN;
  for (double& x : v) x = std::fabs(x);
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}
double rms(const std::vector<double>& v) {
  if (v.empty()) return NAN;
  double s = 0;
  for (double x : v) s += x * x;
  return std::sqrt(s / v.size());
}

// The bias across the curves fitted to the signed distances by Huber IRLS; returns the residuals. For a
// pair only the two models' relative bias across the curves is observable, and an affine bias of either
// image moves the matches across their curves by an affine function of the position: a plane
// c0 + c1 x2 + c2 y2 (kilopixels of image 2). (Terms in both images' coordinates together would not do:
// the signed distance is itself, to first order, a linear function n . q - (J^T n) . p of both positions,
// so such a fit absorbs every match's distance with corrections the size of the image.)
std::vector<double> remove_affine_bias(const Eigen::MatrixXd& xy, const std::vector<double>& dist) {
  const Eigen::Index n = static_cast<Eigen::Index>(dist.size());
  Eigen::MatrixXd A(n, 3);
  Eigen::VectorXd d(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    A(i, 0) = 1, A(i, 1) = xy(i, 2) / 1000, A(i, 2) = xy(i, 3) / 1000;
    d(i) = dist[static_cast<size_t>(i)];
  }
  Eigen::VectorXd w = Eigen::VectorXd::Ones(n), r = d;
  for (int it = 0; it < 10; ++it) {
    const Eigen::VectorXd sw = w.cwiseSqrt();
    const Eigen::VectorXd beta = (sw.asDiagonal() * A).colPivHouseholderQr().solve(sw.cwiseProduct(d));
    r = d - A * beta;
    std::vector<double> rv(r.data(), r.data() + n);
    const double scale = std::max(1e-6, 1.4826 * median_abs(rv));
    for (Eigen::Index i = 0; i < n; ++i) {
      const double u = std::fabs(r(i)) / scale;
      w(i) = u <= kHuber ? 1.0 : kHuber / u;
    }
  }
  return std::vector<double>(r.data(), r.data() + n);
}

std::vector<double> numbers(const std::string& text, const char* option) {
  std::vector<double> v;
  size_t at = 0;
  while (at <= text.size()) {
    const size_t comma = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, comma - at);
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(x)) throw tpkit::UsageError(std::string(option) + ": not a number: '" + item + "'");
    v.push_back(x);
    at = comma + 1;
  }
  return v;
}
}  // namespace

int main(int argc, char** argv) {
  const char* usage = "usage: bench_epipolar_distance IMAGE1 IMAGE2 MATCHES... [--rpc1 MODEL] [--rpc2 MODEL] [--heights LO,HI] [--dump FILE]\n";
  try {
    std::vector<std::string> pos;
    std::string rpc1, rpc2, dump_path;
    std::optional<std::pair<double, double>> heights;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw tpkit::UsageError(a + ": needs a value");
        return argv[++i];
      };
      if (a == "--help" || a == "-h") {
        std::fputs(usage, stdout);
        return 0;
      } else if (a == "--rpc1") {
        rpc1 = value();
      } else if (a == "--rpc2") {
        rpc2 = value();
      } else if (a == "--dump") {
        dump_path = value();
      } else if (a == "--heights") {
        const auto v = numbers(value(), "--heights");
        if (v.size() != 2 || !(v[0] < v[1])) throw tpkit::UsageError("--heights: LO,HI with LO < HI (metres above the ellipsoid)");
        heights = std::make_pair(v[0], v[1]);
      } else if (a.size() > 1 && a[0] == '-') {
        throw tpkit::UsageError(a + ": unknown option");
      } else {
        pos.push_back(a);
      }
    }
    if (pos.size() < 3) throw tpkit::UsageError(std::string("IMAGE1 IMAGE2 MATCHES... expected\n") + usage);
    const tpkit::RpcModel m1 = tpkit::load_rpc_model(rpc1.empty() ? pos[0] : rpc1).model;
    const tpkit::RpcModel m2 = tpkit::load_rpc_model(rpc2.empty() ? pos[1] : rpc2).model;
    const double lo = heights ? heights->first : std::max(m1.height_min(), m2.height_min());
    const double hi = heights ? heights->second : std::min(m1.height_max(), m2.height_max());
    if (!(lo < hi)) throw tpkit::InputError(pos[0] + ", " + pos[1] + ": the models' height ranges do not meet: give --heights");
    FILE* dump = nullptr;
    if (!dump_path.empty()) {
      dump = std::fopen(dump_path.c_str(), "w");
      if (!dump) throw tpkit::InputError(dump_path + ": cannot write");
      std::fprintf(dump, "# file x1 y1 x2 y2 sigma refined d_before d (px of image 2)\n");
    }
    std::printf("# file records refined rms_all_before med_all_before rms_all med_all rms_refined med_refined (px of image 2; heights %.0f..%.0f m)\n", lo, hi);
    for (size_t f = 2; f < pos.size(); ++f) {
      const tpkit::Matches mt = tpkit::read_matches(pos[f]);
      const int refined_col = mt.extra.find("refined");
      std::vector<double> before;
      std::vector<int> kept_refined;
      std::vector<double> kept_sigma;
      const int sigma_col = mt.extra.find("sigma");
      Eigen::MatrixXd kept_xy(static_cast<Eigen::Index>(mt.size()), 4);
      for (size_t i = 0; i < mt.size(); ++i) {
        const Eigen::Index r = static_cast<Eigen::Index>(i);
        const auto c = across_curve(m1, m2, mt.xy.block<1, 2>(r, 0).transpose(), mt.xy.block<1, 2>(r, 2).transpose(), lo, hi);
        if (!c) continue;
        kept_xy.row(static_cast<Eigen::Index>(before.size())) = mt.xy.row(r);
        before.push_back(*c);
        kept_refined.push_back(refined_col < 0 ? 1 : mt.extra.values(r, refined_col) != 0);
        kept_sigma.push_back(sigma_col < 0 ? NAN : mt.extra.values(r, sigma_col));
      }
      kept_xy.conservativeResize(static_cast<Eigen::Index>(before.size()), 4);
      const std::vector<double> after = before.size() >= 3 ? remove_affine_bias(kept_xy, before) : before;
      if (dump)
        for (size_t i = 0; i < after.size(); ++i)
          std::fprintf(dump, "%s %.4f %.4f %.4f %.4f %.5f %d %.5f %.5f\n", pos[f].c_str(), kept_xy(static_cast<Eigen::Index>(i), 0),
                       kept_xy(static_cast<Eigen::Index>(i), 1), kept_xy(static_cast<Eigen::Index>(i), 2), kept_xy(static_cast<Eigen::Index>(i), 3),
                       kept_sigma[i], kept_refined[i], before[i], after[i]);
      std::vector<double> refined;
      for (size_t i = 0; i < after.size(); ++i)
        if (kept_refined[i]) refined.push_back(after[i]);
      std::printf("%s %zu %zu %.4f %.4f %.4f %.4f %.4f %.4f\n", pos[f].c_str(), before.size(), refined.size(), rms(before),
                  median_abs(before), rms(after), median_abs(after), rms(refined), median_abs(refined));
    }
    if (dump) std::fclose(dump);
    return 0;
  } catch (const tpkit::UsageError& e) {
    std::fprintf(stderr, "bench_epipolar_distance: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_epipolar_distance: %s\n", e.what());
    return 1;
  }
}
