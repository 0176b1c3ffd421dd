#include "tpkit/ground/gcp_file.hpp"

#include <algorithm>
#include <cmath>
#include <Eigen/Dense>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/text_table.hpp"

namespace tpkit {

namespace {

double parse_double(const std::string& s, const std::string& source, long line, const std::string& what) {
  size_t used = 0;
  double v = NAN;
  try {
    v = std::stod(s, &used);
  } catch (...) {
    used = 0;
  }
  if (used == 0 || used != s.size()) throw InputError(source, line, what + " '" + s + "' is not a number");
  return v;
}

// The largest id: an integer that a double holds exactly (2^53), for every tpkit table holds its numbers
// as doubles (the accuracy file's id column among them): two larger ids could read back as one.
constexpr double kMaxGcpId = 9007199254740992.0;

long long checked_id(double id, const std::string& text, const std::string& source, long line) {
  if (id != std::floor(id)) throw InputError(source, line, "id '" + text + "' is not an integer");
  if (std::fabs(id) > kMaxGcpId)
    throw InputError(source, line, "id '" + text + "' is beyond 2^53 = 9007199254740992: tpkit keeps ids as numbers, exact up to there (number the points anew)");
  return static_cast<long long>(id);
}

void check_point(const Gcp& g) {
  if (!g.llh.allFinite() || std::fabs(g.llh[1]) > 90 || std::fabs(g.llh[0]) > 360)
    throw InputError(g.source, g.line, "point " + std::to_string(g.id) + ": lon " + format_number(g.llh[0]) + ", lat " +
                                           format_number(g.llh[1]) + ", h " + format_number(g.llh[2]) + " is not a ground position");
  for (int k = 0; k < 3; ++k)
    if (!(g.sigma_enu[k] > 0) || !std::isfinite(g.sigma_enu[k]))
      throw InputError(g.source, g.line, "point " + std::to_string(g.id) + ": ground sigma " + format_number(g.sigma_enu[k]) +
                                             " is not a standard deviation (metres, > 0)");
  for (const auto& m : g.measurements) {
    if (!m.xy.allFinite())
      throw InputError(g.source, m.line, "point " + std::to_string(g.id) + ": a measurement in " + m.image + " that is not a position");
    if (!(m.sigma_px > 0) || !std::isfinite(m.sigma_px))
      throw InputError(g.source, m.line, "point " + std::to_string(g.id) + ": pixel sigma " + format_number(m.sigma_px) +
                                             " in " + m.image + " is not a standard deviation (pixels, > 0)");
  }
}

Eigen::Vector3d ecef_sigma_to_enu(const Eigen::Vector3d& s, double lon, double lat) {
  if (!(s.minCoeff() > 0) || !s.allFinite()) return s;  // refused by check_point with the values given
  const double l = lon * M_PI / 180, p = lat * M_PI / 180;
  Eigen::Matrix3d R;  // rows: east, north, up in ECEF
  R << -std::sin(l), std::cos(l), 0, -std::sin(p) * std::cos(l), -std::sin(p) * std::sin(l), std::cos(p),
      std::cos(p) * std::cos(l), std::cos(p) * std::sin(l), std::sin(p);
  return (R.cwiseAbs2() * s.cwiseAbs2()).cwiseSqrt();
}

// The file's text ('-': standard input; TextInput drops a UTF-8 byte order mark, which editors on Windows
// write and which made the first id "\xEF\xBB\xBF1" or hid the "# tpkit gcp" line), read line by line with
// read_text_line's bound: a device or a binary file fails at its first NUL byte or overlong line instead
// of filling memory.
std::string read_text(const std::string& path) {
  TextInput in(path);
  std::string text, line;
  for (long lineno = 1; read_text_line(in.stream(), line, path, lineno); ++lineno) text.append(line).push_back('\n');
  return text;
}

}  // namespace

std::vector<Gcp> parse_asp_gcp(const std::string& text, const std::string& source) {
  std::vector<Gcp> out;
  std::istringstream in(text);
  std::string line;
  long n = 0;
  std::map<long long, long> seen;
  while (std::getline(in, line)) {
    ++n;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::string fields = line;
    std::replace(fields.begin(), fields.end(), ',', ' ');  // ASP: spaces or commas
    std::istringstream ls(fields);
    std::vector<std::string> f;
    for (std::string w; ls >> w;) f.push_back(w);
    if (f.size() < 7 || (f.size() - 7) % 5 != 0)
      throw InputError(source, n, std::to_string(f.size()) + " fields: an ASP GCP line is 'id lat lon height sigma_x sigma_y sigma_z' "
                                  "and 5 per image 'image col row sigma_col sigma_row'");
    Gcp g;
    g.source = source;
    g.line = n;
    g.id = checked_id(parse_double(f[0], source, n, "id"), f[0], source, n);
    if (seen.count(g.id)) throw InputError(source, n, "point " + f[0] + " is also on line " + std::to_string(seen[g.id]));
    seen[g.id] = n;
    const double lat = parse_double(f[1], source, n, "latitude"), lon = parse_double(f[2], source, n, "longitude");
    g.llh = {lon, lat, parse_double(f[3], source, n, "height")};
    // sigma_x, sigma_y, sigma_z: ECEF metres (bundle_adjust's default); the diagonal of that covariance
    // rotated to east, north, up at the point (exact for equal sigmas, the usual case)
    const Eigen::Vector3d sxyz(parse_double(f[4], source, n, "sigma_x"), parse_double(f[5], source, n, "sigma_y"),
                               parse_double(f[6], source, n, "sigma_z"));
    g.sigma_enu = ecef_sigma_to_enu(sxyz, lon, lat);
    for (size_t k = 7; k < f.size(); k += 5) {
      GcpMeasurement m;
      m.image = f[k];
      m.xy = {parse_double(f[k + 1], source, n, "column"), parse_double(f[k + 2], source, n, "row")};
      const double sc = parse_double(f[k + 3], source, n, "sigma_col"), sr = parse_double(f[k + 4], source, n, "sigma_row");
      if (!(sc > 0) || !(sr > 0) || !std::isfinite(sc) || !std::isfinite(sr))
        throw InputError(source, n, "point " + f[0] + ": pixel sigmas " + f[k + 3] + " " + f[k + 4] + " in " + m.image +
                                        " are not standard deviations (pixels, > 0)");
      // one sigma per measurement: the larger of the two (conservative)
      m.sigma_px = std::max(sc, sr);
      m.line = n;
      g.measurements.push_back(m);
    }
    check_point(g);
    out.push_back(std::move(g));
  }
  if (out.empty()) throw InputError(source, n, "no ground control point in the file");
  return out;
}

std::vector<Gcp> parse_tpkit_gcp(const std::string& text, const std::string& source) {
  ReadOptions opt;
  opt.kind = "gcp";
  opt.may_be_missing = [](const std::string& c) { return c == "x" || c == "y" || c == "sigma_px"; };
  std::istringstream in(text);
  TextTable t = read_table(in, source, opt);
  const char* names[] = {"id", "role", "lon", "lat", "h", "sigma_e", "sigma_n", "sigma_u", "image", "x", "y", "sigma_px"};
  int c[12];
  for (int k = 0; k < 12; ++k) c[k] = t.require(names[k]);
  std::vector<Gcp> out;
  std::map<long long, size_t> index;
  for (size_t r = 0; r < t.rows.size(); ++r) {
    const auto& v = t.rows[r];
    const long line = t.row_line[r];
    const long long id = checked_id(v[c[0]], format_number(v[c[0]]), source, line);
    if (v[c[1]] != 0 && v[c[1]] != 1) throw InputError(source, line, "role " + format_number(v[c[1]]) + ": 0 (control) or 1 (check)");
    Gcp g;
    g.id = id;
    g.role = v[c[1]] == 0 ? GcpRole::control : GcpRole::check;
    g.llh = {v[c[2]], v[c[3]], v[c[4]]};
    g.sigma_enu = {v[c[5]], v[c[6]], v[c[7]]};
    g.source = source;
    g.line = line;
    auto it = index.find(g.id);
    if (it == index.end()) {
      index[g.id] = out.size();
      out.push_back(g);
    } else if (out[it->second].role != g.role || out[it->second].llh != g.llh || out[it->second].sigma_enu != g.sigma_enu) {
      throw InputError(source, line, "point " + std::to_string(g.id) + " has other ground values or role than on line " +
                                         std::to_string(out[it->second].line));
    }
    Gcp& p = out[index[g.id]];
    const double image = v[c[8]];
    if (image == 0 && std::isnan(v[c[9]]) && std::isnan(v[c[10]])) continue;  // a point without a measurement
    if (image != std::floor(image) || image < 1 || image > static_cast<double>(t.images.size()))
      throw InputError(source, line, "image " + format_number(image) + " is not one of the header's image lines (1 to " +
                                         std::to_string(t.images.size()) + ")");
    GcpMeasurement m;
    m.image = t.images[static_cast<size_t>(image) - 1].path;
    m.xy = {v[c[9]], v[c[10]]};
    m.sigma_px = v[c[11]];
    m.line = line;
    for (const auto& o : p.measurements)
      if (o.image == m.image) throw InputError(source, line, "point " + std::to_string(g.id) + " is measured twice in " + m.image);
    p.measurements.push_back(m);
  }
  for (const auto& g : out) check_point(g);
  if (out.empty()) throw InputError(source, 0, "no ground control point in the file");
  return out;
}

std::vector<Gcp> read_gcp_file(const std::string& path) {
  const std::string text = read_text(path);
  const std::string source = path == "-" ? "<stdin>" : path;
  const std::string first = text.substr(0, text.find('\n'));
  if (first.rfind("# tpkit gcp", 0) == 0) return parse_tpkit_gcp(text, source);
  if (first.rfind("# tpkit ", 0) == 0) throw InputError(source, 1, "a " + first.substr(8) + " file: ground control points are a gcp file");
  return parse_asp_gcp(text, source);
}

std::vector<Gcp> read_gcp_files(const std::vector<std::string>& paths) {
  namespace fs = std::filesystem;
  for (size_t i = 0; i < paths.size(); ++i)
    for (size_t j = 0; j < i; ++j) {
      std::error_code ec;
      if (paths[i] == paths[j] || (paths[i] != "-" && paths[j] != "-" && fs::equivalent(paths[i], paths[j], ec)))
        throw InputError(paths[i] == "-" ? "<stdin>" : paths[i], 0,
                         "given twice (also as " + paths[j] + "): its points would count twice in the fit");
    }
  std::vector<Gcp> out;
  std::map<long long, size_t> first;  // id -> its point in out
  for (const auto& path : paths)
    for (Gcp& g : read_gcp_file(path)) {
      const auto [it, fresh] = first.emplace(g.id, out.size());
      if (!fresh)
        throw InputError(g.source, g.line, "point " + std::to_string(g.id) + " is also " + out[it->second].source + ":" +
                                               std::to_string(out[it->second].line) + ": one id is one point (a point given twice would count twice)");
      out.push_back(std::move(g));
    }
  return out;
}

std::string format_tpkit_gcp(const std::vector<Gcp>& gcps) {
  std::vector<ImageRef> images;
  std::map<std::string, int> number;
  for (const auto& g : gcps)
    for (const auto& m : g.measurements)
      if (!number.count(m.image)) {
        number[m.image] = static_cast<int>(images.size()) + 1;
        images.push_back({m.image, 0, 0});
      }
  Meta meta;
  meta_set(meta, "role", "0: control (used in the fit), 1: check (never used in the fit)");
  meta_set(meta, "units", "lon lat degrees, h m above the WGS 84 ellipsoid, sigma_e/n/u m, x y sigma_px pixels");
  std::ostringstream os;
  write_header(os, "gcp", 1, images, meta,
               {"id", "role", "lon", "lat", "h", "sigma_e", "sigma_n", "sigma_u", "image", "x", "y", "sigma_px"});
  for (const auto& g : gcps) {
    const std::vector<double> head = {static_cast<double>(g.id), static_cast<double>(g.role), g.llh[0], g.llh[1], g.llh[2],
                                      g.sigma_enu[0], g.sigma_enu[1], g.sigma_enu[2]};
    if (g.measurements.empty()) {
      auto v = head;
      v.insert(v.end(), {0, NAN, NAN, NAN});
      write_record(os, v);
    }
    for (const auto& m : g.measurements) {
      auto v = head;
      v.insert(v.end(), {static_cast<double>(number[m.image]), m.xy[0], m.xy[1], m.sigma_px});
      write_record(os, v);
    }
  }
  return os.str();
}

}  // namespace tpkit
