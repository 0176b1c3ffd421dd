// See rpc_points.hpp.
#include "tpkit/rpc/rpc_points.hpp"

#include "tpkit/rpc/rpc_ground.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <ostream>
#include <string_view>
#include <vector>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/rpc/dem_prior.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_ground.hpp"

namespace tpkit {

namespace {

bool blank(char c) { return c == ' ' || c == '\t'; }

// The first `n` blank-separated fields of `line` as finite numbers, and where the rest begins (the
// separator before the first extra column included, so that it is kept as it was).
std::vector<double> leading_numbers(const std::string& line, int n, size_t& rest, const std::string& source, long lineno) {
  std::vector<double> v;
  size_t i = 0;
  while (static_cast<int>(v.size()) < n) {
    while (i < line.size() && blank(line[i])) ++i;
    if (i >= line.size() || line[i] == '\r')
      throw InputError(source, lineno, "expected " + std::to_string(n) + " numbers, got " + std::to_string(v.size()));
    size_t j = i;
    while (j < line.size() && !blank(line[j]) && line[j] != '\r') ++j;
    const std::string field = line.substr(i, j - i);
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(field.c_str(), &end);
    // nan is a point without a value (what an earlier stage writes for a point it could not solve)
    if (end != field.c_str() + field.size() || std::isinf(x) || errno == ERANGE)
      throw InputError(source, lineno, "'" + field + "' is not a finite number (nor nan)");
    v.push_back(x);
    i = j;
  }
  rest = i;
  return v;
}


// The height where the line of sight of pixel (x, y) meets the DEM: f(h) = DEM(localize(x, y, h)) - h
// sampled at 65 heights over the model's height range, the highest sign change (the first surface the
// ray meets coming down from the satellite) refined by bisection to 0.1 mm.
double line_of_sight_on_dem(const RpcModel& m, const HeightPrior& ground, double x, double y) {
  auto f = [&](double h, double& out) {
    const Eigen::Vector2d ll = m.localize(x, y, h);
    double hd = 0;
    if (!ground.at(ll.x(), ll.y(), hd, nullptr)) return false;
    out = hd - h;
    return true;
  };
  const int n = 64;
  const double lo = m.height_min(), hi = m.height_max();
  double h_prev = 0, f_prev = 0;
  bool have_prev = false, seen = false;
  for (int k = n; k >= 0; --k) {  // from the top down
    const double h = lo + (hi - lo) * k / n;
    double fh = 0;
    if (!f(h, fh)) {
      have_prev = false;
      continue;
    }
    seen = true;
    if (fh == 0) return h;
    if (have_prev && (fh > 0) != (f_prev > 0)) {
      double a = h, b = h_prev, fa = fh;  // f(a) and f(b) of opposite signs, a < b
      while (b - a > 1e-4) {
        const double c = 0.5 * (a + b);
        double fc = 0;
        if (!f(c, fc)) throw NumericalError("the DEM has a hole under the line of sight near h = " + format_number(c) + " m");
        if ((fc > 0) == (fa > 0)) a = c, fa = fc;
        else b = c;
      }
      return 0.5 * (a + b);
    }
    h_prev = h, f_prev = fh, have_prev = true;
  }
  if (!seen) throw NumericalError("the DEM has no height under the line of sight at any height of the model (" +
                                  format_number(lo) + " .. " + format_number(hi) + " m)");
  throw NumericalError("the line of sight does not meet the DEM between " + format_number(lo) + " and " + format_number(hi) + " m");
}

}  // namespace

void transform_rpc_points(std::istream& in, const std::string& source, std::ostream& out, const RpcModel& model,
                          RpcPointDirection direction, const ReferenceDem* dem, RpcPointStats* stats, const GroundConverter* crs) {
  RpcPointStats st;
  std::string line;
  HeightPrior ground;
  if (dem) ground = reference_dem_prior(std::shared_ptr<const ReferenceDem>(dem, [](const ReferenceDem*) {}), 1);  // not owned
  const int columns = direction == RpcPointDirection::Localize && dem ? 2 : 3;
  for (long lineno = 1; read_text_line(in, line, source, lineno); ++lineno) {
    size_t first = 0;
    while (first < line.size() && blank(line[first])) ++first;
    if (first == line.size() || line[first] == '#' || line[first] == '\r') {
      out << line << '\n';
      ++st.comments;
      continue;
    }
    size_t rest = 0;
    const std::vector<double> v = leading_numbers(line, columns, rest, source, lineno);
    double a = 0, b = 0, h = columns == 3 ? v[2] : 0, c = 0;
    try {
      for (double x : v)
        if (std::isnan(x)) throw NumericalError("the input point is nan");
      if (direction == RpcPointDirection::Project) {
        const Eigen::Vector3d g = crs ? crs->inverse({v[0], v[1], v[2]}) : Eigen::Vector3d(v[0], v[1], h);
        if (const std::string why = model.outside_domain(g); !why.empty()) throw NumericalError(why);
        const Eigen::Vector2d xy = model.project(g);
        if (!xy.allFinite()) throw NumericalError("the projection is not finite (a pole of the model)");
        a = xy.x(), b = xy.y(), h = g.z();
        st.outside += model.outside_validity_box(g);
      } else if (!dem) {
        const Eigen::Vector2d ll = model.localize(v[0], v[1], h);
        a = ll.x(), b = ll.y();
        st.outside += model.outside_validity_box({a, b, h});
      } else {
        h = line_of_sight_on_dem(model, ground, v[0], v[1]);
        const Eigen::Vector2d ll = model.localize(v[0], v[1], h);
        a = ll.x(), b = ll.y();
        st.outside += model.outside_validity_box({a, b, h});
      }
      c = h;
      if (crs && direction == RpcPointDirection::Localize) {
        const Eigen::Vector3d p = crs->checked({a, b, h});
        a = p.x(), b = p.y(), c = p.z();
      }
    } catch (const NumericalError& e) {
      // no solution for this point (it is no bad input): marked nan, counted, the first reason kept
      if (st.unsolved++ == 0) st.first_unsolved = source + ":" + std::to_string(lineno) + ": " + e.what();
      out << "nan nan nan" << std::string_view(line).substr(rest) << '\n';
      continue;
    }
    out << format_number(a) << ' ' << format_number(b) << ' ' << format_number(c) << std::string_view(line).substr(rest) << '\n';
    ++st.points;
  }
  if (stats) *stats = st;
}

}  // namespace tpkit
