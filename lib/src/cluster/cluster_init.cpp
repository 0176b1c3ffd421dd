// See cluster_init.hpp.
#include "tpkit/cluster/cluster_init.hpp"

#include <GeographicLib/LocalCartesian.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>

#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"

namespace tpkit {

LookAngles look_angles(double sat_lat, double sat_lon, double sat_h, double lat, double lon, double h) {
  GeographicLib::LocalCartesian lc(lat, lon, h);
  double e, n, u;
  lc.Forward(sat_lat, sat_lon, sat_h, e, n, u);
  LookAngles a;
  a.rho = std::sqrt(e * e + n * n + u * u);
  a.alpha = std::atan2(n, e);
  a.beta = a.rho > 0 ? std::asin(u / a.rho) : 0;
  return a;
}

namespace {
std::string trim(const std::string& s) {
  size_t a = s.find_first_not_of(" \t\r"), b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

const std::set<std::string>& known_keys() {
  static const std::set<std::string> k = [] {
    std::set<std::string> s;
    for (const auto& n : physical_param_names()) s.insert(n);
    for (const char* v : {"1", "2"})
      for (const char* b : {"sat", "scene"})
        for (const char* c : {"_lat", "_lon", "_h"}) s.insert(std::string(b) + v + c);
    for (const char* c : {"origin_lat", "origin_lon", "origin_h"}) s.insert(c);
    for (int r = 1; r <= 3; ++r)
      for (int c = 1; c <= 3; ++c) s.insert("h" + std::to_string(r) + std::to_string(c));
    return s;
  }();
  return k;
}
}  // namespace

ClusterInit read_cluster_init(std::istream& in, const std::string& source) {
  std::map<std::string, std::pair<double, long>> kv;
  std::string line;
  long lineno = 0;
  while (read_text_line(in, line, source, ++lineno)) {
    size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    line = trim(line);
    if (line.empty()) continue;
    size_t eq = line.find('=');
    if (eq == std::string::npos) throw InputError(source, lineno, "expected 'key = value', got '" + line + "'");
    std::string key = trim(line.substr(0, eq)), val = trim(line.substr(eq + 1));
    if (!known_keys().count(key)) throw InputError(source, lineno, "unknown key '" + key + "'");
    if (kv.count(key)) throw InputError(source, lineno, "key '" + key + "' given twice");
    char* end = nullptr;
    double v = val.empty() ? 0 : std::strtod(val.c_str(), &end);
    if (val.empty() || end != val.c_str() + val.size()) throw InputError(source, lineno, "value of '" + key + "' is not a number: '" + val + "'");
    if (!std::isfinite(v)) throw InputError(source, lineno, "value of '" + key + "' is not finite");
    kv[key] = {v, lineno};
  }
  if (kv.empty()) throw InputError(source, 0, "no parameters in the init file");
  auto has = [&](const std::string& k) { return kv.count(k) > 0; };
  auto get = [&](const std::string& k, double def) { return has(k) ? kv[k].first : def; };
  auto where = [&](const std::string& k) { return has(k) ? kv[k].second : 0L; };
  ClusterInit ci;
  // Homography start.
  int nh = 0;
  for (int r = 1; r <= 3; ++r)
    for (int c = 1; c <= 3; ++c) nh += has("h" + std::to_string(r) + std::to_string(c));
  if (nh > 0) {
    if (nh != 9) throw InputError(source, 0, "a homography start needs all nine keys h11 ... h33");
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) ci.H(r, c) = kv["h" + std::to_string(r + 1) + std::to_string(c + 1)].first;
    if (std::abs(ci.H.determinant()) < 1e-12 * std::pow(ci.H.norm(), 3))
      throw InputError(source, 0, "the homography h11 ... h33 is singular");
    ci.has_H = true;
  }
  bool any_physical = false;
  for (const auto& p : kv)
    if (p.first[0] != 'h' || p.first.size() != 3) any_physical = true;
  if (!any_physical) return ci;
  // Ground frame origin for geodetic target points.
  bool geo_origin = has("origin_lat") || has("scene1_lat");
  double olat = get("origin_lat", get("scene1_lat", 0)), olon = get("origin_lon", get("scene1_lon", 0)),
         oh = get("origin_h", get("scene1_h", 0));
  if (std::abs(olat) > 90) throw InputError(source, where("origin_lat"), "origin_lat outside [-90, 90] degrees");
  for (int v = 0; v < 2; ++v) {
    std::string s = std::to_string(v + 1);
    ViewParams& q = ci.physical.view[v];
    bool geo = has("sat" + s + "_lat") || has("sat" + s + "_lon") || has("sat" + s + "_h") || has("scene" + s + "_lat") ||
               has("scene" + s + "_lon") || has("scene" + s + "_h");
    if (geo) {
      for (const char* k : {"sat", "scene"})
        for (const char* c : {"_lat", "_lon", "_h"})
          if (!has(k + s + c)) throw InputError(source, 0, "geodetic positions of image " + s + " need " + k + s + c);
      for (const char* k : {"px", "py", "rho", "alpha", "beta"})
        if (has(k + s))
          throw InputError(source, where(k + s), std::string(k) + s + " cannot be given with geodetic positions of image " + s);
      for (const char* k : {"sat", "scene"})
        if (std::abs(get(k + s + "_lat", 0)) > 90)
          throw InputError(source, where(k + s + "_lat"), std::string(k) + s + "_lat outside [-90, 90] degrees");
      LookAngles la = look_angles(get("sat" + s + "_lat", 0), get("sat" + s + "_lon", 0), get("sat" + s + "_h", 0),
                                  get("scene" + s + "_lat", 0), get("scene" + s + "_lon", 0), get("scene" + s + "_h", 0));
      if (!(la.beta > 0)) throw InputError(source, where("sat" + s + "_lat"), "satellite " + s + " is below the horizon of its scene");
      q.rho = la.rho, q.alpha = la.alpha, q.beta = la.beta;
      GeographicLib::LocalCartesian lc(olat, olon, oh);
      double e, n, u;
      lc.Forward(get("scene" + s + "_lat", 0), get("scene" + s + "_lon", 0), get("scene" + s + "_h", 0), e, n, u);
      q.px = e, q.py = n;
    } else {
      (void)geo_origin;
      for (const char* k : {"rho", "alpha", "beta"})
        if (!has(k + s)) throw InputError(source, 0, "missing key " + std::string(k) + s + " (or geodetic positions sat" + s + "_* scene" + s + "_*)");
      q.px = get("px" + s, 0), q.py = get("py" + s, 0), q.rho = get("rho" + s, 0);
      q.alpha = get("alpha" + s, 0), q.beta = get("beta" + s, 0);
    }
    if (!has("res" + s)) throw InputError(source, 0, "missing key res" + s + " (metres per pixel)");
    q.gamma = get("gamma" + s, 0), q.res = get("res" + s, 0), q.theta = get("theta" + s, 0);
    q.cx = get("cx" + s, 0), q.cy = get("cy" + s, 0);
  }
  std::string why = physical_params_problem(ci.physical);
  if (!why.empty()) {
    // Point at the line of the offending key when there is one.
    long ln = 0;
    for (const auto& p : kv)
      if (why.compare(0, p.first.size() + 1, p.first + " ") == 0) ln = p.second.second;
    throw InputError(source, ln, why);
  }
  ci.has_physical = true;
  return ci;
}

ClusterInit read_cluster_init_file(const std::string& path) {
  std::ifstream f = open_input_file(path);  // "no such file", "is a directory"; read with the line bound
  return read_cluster_init(f, path);
}

}  // namespace tpkit
