// The synthetic satellite triplet of tp-synth: parameters, geometry, truth points (synth_scene.hpp).
#include "tpkit/synth/synth_scene.hpp"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/cpu_dispatch.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/version.hpp"
#include "tpkit/synth/synth_camera.hpp"
#include "tpkit/synth/synth_conditions.hpp"
#include "tpkit/synth/synth_noise.hpp"
#include "tpkit/synth/synth_structures.hpp"
#include "tpkit/synth/synth_terrain.hpp"
#include "tpkit/synth/synth_texture.hpp"

namespace tpkit {

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180;
constexpr double kAltitude = 700e3;  // satellite altitude above the scene centre (m)
constexpr double kMaxCrossTrack = 30;  // degrees: |--cross-track| beyond this is refused
// Version of the scene model (terrain, texture, cameras, rendering) written to scene.params: bump it when
// the same parameters would give another scene, so that load() refuses files of another version.
constexpr int kSynthModel = 1;
}  // namespace

struct SynthScene::Impl {
  SynthParams p;
  double S = 0;         // scene square side (m)
  double z_top = 0;     // ray origins of affine views: just above the highest terrain
  SynthTerrain terrain;
  SynthTexture texture;
  std::vector<SynthCamera> cam;
  std::vector<double> gain, offset;
  std::vector<Eigen::Vector3d> angles;  // along, cross, roll (deg) per view
  Eigen::Vector3d sun = Eigen::Vector3d::UnitZ();
  SynthStructures structures;            // buildings and trees (empty by default)
  std::vector<Eigen::Vector3d> date_sun;  // per date (scenes with structures)
  std::unique_ptr<SynthScene> sharp;    // SynthParams::blur > 0: the scene seen by ideal sensors
};

int synth_dates(const SynthParams& p) { return p.dates > 0 ? p.dates : std::max(1, p.views / 3); }

void check_params(const SynthParams& p) {
  // 40000: a full Pléiades scene. Beyond it a run takes days and its terrain grid alone gigabytes (man page).
  if (p.size < 16 || p.size > 40000) throw UsageError("--size must be between 16 and 40000 pixels, got " + std::to_string(p.size));
  if (!(p.relief >= 0) || !std::isfinite(p.relief)) throw UsageError("--relief must be >= 0 metres");
  if (!(p.gsd > 0) || !std::isfinite(p.gsd)) throw UsageError("--gsd must be > 0 metres/pixel");
  if (p.camera != "affine" && p.camera != "perspective")
    throw UsageError("--camera must be affine or perspective, got '" + p.camera + "'");
  if (p.points < 0) throw UsageError("--points must be >= 0");
  if (!(p.noise >= 0) || !std::isfinite(p.noise)) throw UsageError("--noise must be >= 0 DN");
  if (!(p.date2 >= 0 && p.date2 <= 1)) throw UsageError("--second-date must be between 0 and 1");
  for (const auto& [opt, v] : {std::pair<const char*, double>{"--clouds", p.clouds}, {"--water", p.water}, {"--nodata-band", p.nodata}})
    if (!(v >= 0 && v <= 0.8)) throw UsageError(std::string(opt) + " must be a fraction between 0 and 0.8");
  if (p.supersample < 1 || p.supersample > 16) throw UsageError("--supersample must be between 1 and 16");
  if (!(p.blur >= 0 && p.blur <= 5)) throw UsageError("--blur must be between 0 and 5 pixels, got " + format_number(p.blur));
  if (!(p.resolution_ratio >= 1 && p.resolution_ratio <= 4))
    throw UsageError("--resolution-ratio must be between 1 and 4, got " + format_number(p.resolution_ratio));
  if (!(p.rotation >= -180 && p.rotation <= 180))
    throw UsageError("--rotation must be between -180 and 180 degrees, got " + format_number(p.rotation));
  if (!(p.buildings >= 0 && p.buildings <= 1)) throw UsageError("--buildings must be a fraction between 0 and 1, got " + format_number(p.buildings));
  if (!(p.trees >= 0 && p.trees <= 1)) throw UsageError("--trees must be a fraction between 0 and 1, got " + format_number(p.trees));
  if (p.views < 2 || p.views > kMaxSynthViews)
    throw UsageError("--views must be between 2 and " + std::to_string(kMaxSynthViews) + ", got " + std::to_string(p.views));
  if (p.dates < 0 || p.dates > p.views)
    throw UsageError("--dates must be between 1 and --views (" + std::to_string(p.views) + "), got " + std::to_string(p.dates));
  if (p.dates == 0 && p.views % 3 != 0)
    throw UsageError("--views " + std::to_string(p.views) + " is not a multiple of 3 (tri-stereo dates): give --dates");
  const int dates = synth_dates(p);
  if (p.views % dates != 0 || p.views / dates > kMaxSynthViewsPerDate)
    throw UsageError("--views " + std::to_string(p.views) + " must be --dates (" + std::to_string(dates) + ") times 1 to " +
                     std::to_string(kMaxSynthViewsPerDate) + " views per date");
  const size_t nct = p.cross_track.size();
  if (!synth_is_block(p)) {
    if (nct != 0 && nct != 1 && nct != 3)
      throw UsageError("--cross-track takes one angle or three, got " + std::to_string(nct));
  } else if (nct != 0 && nct != 1 && nct != static_cast<size_t>(dates) && nct != static_cast<size_t>(p.views)) {
    throw UsageError("--cross-track takes one angle, one per date (" + std::to_string(dates) + ") or one per view (" +
                     std::to_string(p.views) + "), got " + std::to_string(nct));
  }
  for (double c : p.cross_track)
    if (!(std::fabs(c) <= kMaxCrossTrack))
      throw UsageError("--cross-track angles must be between -30 and 30 degrees, got " + format_number(c));
}

void apply_scene_preset(const std::string& name, SynthParams& p) {
  if (name == "buildings") {
    p.buildings = 0.45;
    p.trees = 0.35;
  } else if (name != "default") {
    throw UsageError("--scene must be default or buildings, got '" + name + "'");
  }
}

std::vector<double> parse_cross_track(const std::string& s) {
  std::vector<double> out;
  size_t b = 0;
  while (true) {
    const size_t e = s.find(',', b);
    const std::string item = s.substr(b, e == std::string::npos ? std::string::npos : e - b);
    size_t used = 0;
    double v = NAN;
    try {
      v = std::stod(item, &used);
    } catch (...) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(v))
      throw UsageError("--cross-track: not an angle in degrees: '" + item + "' (DEG or DEG,DEG,DEG)");
    out.push_back(v);
    if (e == std::string::npos) break;
    b = e + 1;
  }
  for (double c : out)
    if (!(std::fabs(c) <= kMaxCrossTrack))
      throw UsageError("--cross-track angles must be between -30 and 30 degrees, got " + format_number(c));
  return out;
}

namespace {
std::string cross_track_text(const std::vector<double>& c) {
  std::string s;
  for (size_t i = 0; i < c.size(); ++i) s += (i ? "," : "") + format_number(c[i]);
  return s;
}
}  // namespace

void save_params(const std::string& path, const SynthParams& p) {
  std::ostringstream os;
  os << "# tpkit synth-params 1\n"
     << "# written-by: " << written_by() << "\n"
     << "seed = " << p.seed << "\n"
     << "size = " << p.size << "\n"
     << "relief = " << format_number(p.relief) << "\n"
     << "gsd = " << format_number(p.gsd) << "\n"
     << "camera = " << p.camera << "\n"
     << "points = " << p.points << "\n"
     << "noise = " << format_number(p.noise) << "\n"
     << "supersample = " << p.supersample << "\n";
  if (!p.cross_track.empty()) os << "cross_track = " << cross_track_text(p.cross_track) << "\n";  // default: no key
  if (synth_is_block(p)) os << "views = " << p.views << "\n" << "dates = " << synth_dates(p) << "\n";  // triplet: no keys
  // conditions: keys only when set (the default scene's file is unchanged)
  for (const auto& [key, v] : {std::pair<const char*, double>{"date2", p.date2}, {"clouds", p.clouds}, {"water", p.water}, {"nodata", p.nodata}})
    if (v != 0) os << key << " = " << format_number(v) << "\n";
  // sensor of views 2..N: keys only when set
  if (p.blur != 0) os << "blur = " << format_number(p.blur) << "\n";
  if (p.resolution_ratio != 1) os << "resolution_ratio = " << format_number(p.resolution_ratio) << "\n";
  if (p.rotation != 0) os << "rotation = " << format_number(p.rotation) << "\n";
  // structures: keys only when set
  if (p.buildings != 0) os << "buildings = " << format_number(p.buildings) << "\n";
  if (p.trees != 0) os << "trees = " << format_number(p.trees) << "\n";
  os << "model = " << kSynthModel << "\n";
  write_file_atomic(path, os.str());
}

SynthParams load_params(const std::string& path) {
  std::ifstream in = open_input_file(path, InputKind::file);
  SynthParams p;
  std::string line;
  long n = 0;
  auto trim = [](std::string s) {
    const auto b = s.find_first_not_of(" \t\r"), e = s.find_last_not_of(" \t\r");
    return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
  };
  while (read_text_line(in, line, path, n + 1)) {
    ++n;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const auto eq = t.find('=');
    if (eq == std::string::npos) throw InputError(path, n, "expected 'key = value'");
    const std::string key = trim(t.substr(0, eq)), val = trim(t.substr(eq + 1));
    auto num = [&](double& out) {
      size_t used = 0;
      try {
        out = std::stod(val, &used);
      } catch (...) {
        used = 0;
      }
      if (used == 0 || used != val.size() || !std::isfinite(out)) throw InputError(path, n, key + ": not a number: '" + val + "'");
    };
    auto integer = [&](long long& out) {
      size_t used = 0;
      try {
        out = std::stoll(val, &used);
      } catch (...) {
        used = 0;
      }
      if (used == 0 || used != val.size()) throw InputError(path, n, key + ": not an integer: '" + val + "'");
    };
    long long i = 0;
    if (key == "seed") {
      size_t used = 0;
      try {
        p.seed = std::stoull(val, &used);
      } catch (...) {
        used = 0;
      }
      if (used == 0 || used != val.size() || val[0] == '-') throw InputError(path, n, "seed: not an unsigned integer: '" + val + "'");
    } else if (key == "size") {
      integer(i);
      p.size = static_cast<long>(i);
    } else if (key == "relief") {
      num(p.relief);
    } else if (key == "gsd") {
      num(p.gsd);
    } else if (key == "camera") {
      p.camera = val;
    } else if (key == "points") {
      integer(i);
      p.points = static_cast<long>(i);
    } else if (key == "noise") {
      num(p.noise);
    } else if (key == "supersample") {
      integer(i);
      p.supersample = static_cast<long>(i);
    } else if (key == "cross_track") {
      try {
        p.cross_track = parse_cross_track(val);
      } catch (const UsageError& e) {
        throw InputError(path, n, std::string("cross_track: ") + e.what());
      }
    } else if (key == "views") {
      integer(i);
      if (i < 0 || i > kMaxSynthViews) throw InputError(path, n, "views: out of range: '" + val + "'");
      p.views = static_cast<int>(i);
    } else if (key == "dates") {
      integer(i);
      if (i < 0 || i > kMaxSynthViews) throw InputError(path, n, "dates: out of range: '" + val + "'");
      p.dates = static_cast<int>(i);
    } else if (key == "date2") {
      num(p.date2);
    } else if (key == "clouds") {
      num(p.clouds);
    } else if (key == "water") {
      num(p.water);
    } else if (key == "nodata") {
      num(p.nodata);
    } else if (key == "blur") {
      num(p.blur);
    } else if (key == "resolution_ratio") {
      num(p.resolution_ratio);
    } else if (key == "rotation") {
      num(p.rotation);
    } else if (key == "buildings") {
      num(p.buildings);
    } else if (key == "trees") {
      num(p.trees);
    } else if (key == "model") {
      integer(i);
      if (i != kSynthModel)
        throw InputError(path, n, "written by scene model " + val + "; this tpkit has model " + std::to_string(kSynthModel) +
                                      ": regenerate it with this tp-synth");
    } else {
      throw InputError(path, n, "unknown key '" + key + "'");
    }
  }
  try {
    check_params(p);
  } catch (const UsageError& e) {
    throw InputError(path, 0, e.what());
  }
  return p;
}

SynthScene::SynthScene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SynthScene::SynthScene(SynthScene&&) noexcept = default;
SynthScene& SynthScene::operator=(SynthScene&&) noexcept = default;
SynthScene::~SynthScene() = default;

SynthScene SynthScene::load(const std::string& dir) { return SynthScene(load_params(dir + "/scene.params")); }

SynthScene::SynthScene(const SynthParams& params) : impl_(std::make_unique<Impl>()) {
  check_params(params);
  Impl& m = *impl_;
  m.p = params;
  m.p.dates = synth_dates(params);
  const int N = params.views;
  m.cam.resize(N);
  m.gain.resize(N);
  m.offset.resize(N);
  m.angles.resize(N);
  const uint64_t gs = synth::hash(params.seed, 0x6e0);
  auto u = [&](int k) { return synth::uniform(gs, k); };
  const bool affine = params.camera == "affine";
  const long n = params.size;
  // Sensor of views 2..N (synth_sensor.hpp): focal length / resolution_ratio, roll + rotation; view 1 and the
  // defaults untouched (so the default scene is the same to the bit).
  auto sensor_focal = [&](int v, double focal) {
    return v > 0 && params.resolution_ratio != 1 ? focal / params.resolution_ratio : focal;
  };
  auto sensor_roll = [&](int v, double roll) { return v > 0 && params.rotation != 0 ? roll + params.rotation * kDeg : roll; };
  if (!synth_is_block(params)) {
    // Three-line geometry: along-track +22 / 0 / -22 deg (forward, nadir, backward) with small seeded
    // deviations, the same cross-track pointing (2..3 deg) give or take 0.3 deg, small rolls; or the
    // cross-track angles of params.cross_track (one for all views: coplanar viewing directions).
    const double cross = (2.0 + 1.0 * u(1)) * kDeg;
    const std::vector<double>& ct = params.cross_track;
    double along[kViews], crossv[kViews], roll[kViews];
    for (int v = 0; v < kViews; ++v) {
      along[v] = ((v == 0 ? 22.0 : v == 2 ? -22.0 : 0.0) + 0.5 * (2 * u(10 + v) - 1)) * kDeg;
      crossv[v] = ct.empty() ? cross + 0.3 * (2 * u(20 + v) - 1) * kDeg : ct[ct.size() == 3 ? v : 0] * kDeg;
      roll[v] = sensor_roll(v, 0.4 * (2 * u(30 + v) - 1) * kDeg);
      m.gain[v] = 3000 + 600 * u(40 + v);
      m.offset[v] = 60 + 200 * u(50 + v);
      m.angles[v] = Eigen::Vector3d(along[v], crossv[v], roll[v]) / kDeg;
    }
    // Focal length (pixels): the nadir view's pixel spans gsd at the scene centre's range.
    const double range1 = kAltitude * Eigen::Vector3d(std::tan(crossv[1]), std::tan(along[1]), 1).norm();
    const double focal = range1 / params.gsd;
    auto build = [&](double S) {
      const Eigen::Vector3d centre(S / 2, S / 2, 0);
      for (int v = 0; v < kViews; ++v)
        m.cam[v] = make_synth_camera(affine, along[v], crossv[v], roll[v], kAltitude, sensor_focal(v, focal), centre, n);
    };
    // The scene square: the largest S for which the box [0, S]^2 x [-relief/2, relief/2] projects inside
    // every view with a margin of max(4, 3% of size) pixels.
    const double margin = std::max(4.0, 0.03 * n);
    auto fits = [&](double S) {
      build(S);
      for (int v = 0; v < kViews; ++v)
        for (int k = 0; k < 8; ++k) {
          const Eigen::Vector3d X((k & 1) ? S : 0, (k & 2) ? S : 0, (k & 4) ? params.relief / 2 : -params.relief / 2);
          const Eigen::Vector2d x = m.cam[v].project(X);
          if (!(x.x() >= margin && x.y() >= margin && x.x() <= n - 1 - margin && x.y() <= n - 1 - margin)) return false;
        }
      return true;
    };
    double lo = 0, hi = 2 * n * params.gsd;
    if (!fits(1e-6 * params.gsd))
      throw UsageError("--relief " + format_number(params.relief) + " m is too large for views of " + std::to_string(n) +
                       " pixels at --gsd " + format_number(params.gsd));
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (fits(mid) ? lo : hi) = mid;
    }
    m.S = lo;
    build(m.S);
  } else {
    // Block (synth_scene.hpp): its own stream of random numbers, so that the tri-stereo above is unchanged.
    const int D = m.p.dates, k = N / D;
    const uint64_t bs = synth::hash(params.seed, 0xb10c);
    auto ub = [&](int a, int b) { return synth::uniform(bs, a, b); };
    const std::vector<double>& ct = params.cross_track;
    std::vector<double> along(N), crossv(N), roll(N);
    for (int v = 0; v < N; ++v) {
      const int d = v / k, i = v % k;
      const double base = k == 1 ? 0.0 : 22.0 - 44.0 * i / (k - 1);
      along[v] = (base + 0.5 * (2 * ub(1, v) - 1)) * kDeg;
      const double date_cross = (d % 2 == 0 ? 1 : -1) * (3 + 9 * ub(2, d));
      const double c = ct.empty() ? date_cross : ct.size() == 1 ? ct[0] : ct.size() == static_cast<size_t>(N) ? ct[v] : ct[d];
      crossv[v] = c * kDeg;
      roll[v] = sensor_roll(v, (1.0 * (2 * ub(3, d) - 1) + 0.2 * (2 * ub(4, v) - 1)) * kDeg);
      m.gain[v] = 3000 + 600 * ub(5, v);
      m.offset[v] = 60 + 200 * ub(6, v);
      m.angles[v] = Eigen::Vector3d(along[v], crossv[v], roll[v]) / kDeg;
    }
    const double focal = kAltitude / params.gsd;
    // Footprint extents (bounding box on Z = 0, m) of each view looking at the origin.
    std::vector<Eigen::Vector2d> ext(N);
    for (int v = 0; v < N; ++v) {
      m.cam[v] = make_synth_camera(affine, along[v], crossv[v], roll[v], kAltitude, sensor_focal(v, focal), Eigen::Vector3d::Zero(), n);
      Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
      for (int c = 0; c < 4; ++c) {
        Eigen::Vector3d o, dir;
        m.cam[v].ray((c & 1) ? n - 0.5 : -0.5, (c & 2) ? n - 0.5 : -0.5, 0, o, dir);
        const Eigen::Vector3d X = o + (o.z() / -dir.z()) * dir;
        lo = lo.cwiseMin(X.head<2>());
        hi = hi.cwiseMax(X.head<2>());
      }
      ext[v] = hi - lo;
    }
    // Window centres: view i + 1 of a date lies south of view i by the mean of their along-track (Y) extents
    // less f_i times the smaller one (their extents then overlap by f_i of the smaller); date d + 1 lies east of
    // date d likewise with g_d and the dates' mean cross-track (X) extents; f in [0.58, 0.68] (the first and
    // last views of a tri-stereo date still overlap by about a quarter), g in [0.45, 0.6]; plus +-2% of the
    // extent on each axis.
    std::vector<double> f(static_cast<size_t>(k), 0.5), g(static_cast<size_t>(D), 0.5);
    for (int i = 0; i < k; ++i) f[i] = 0.58 + 0.1 * ub(7, i);
    for (int d = 0; d < D; ++d) g[d] = 0.45 + 0.15 * ub(8, d);
    auto mean_ext = [&](int d, int axis) {
      double s = 0;
      for (int i = 0; i < k; ++i) s += ext[d * k + i][axis];
      return s / k;
    };
    std::vector<Eigen::Vector2d> centre(N);
    double xd = 0;
    for (int d = 0; d < D; ++d) {
      if (d > 0) {
        const double a = mean_ext(d - 1, 0), b = mean_ext(d, 0);
        xd += 0.5 * (a + b) - g[d - 1] * std::min(a, b);
      }
      double yi = 0;
      for (int i = 0; i < k; ++i) {
        const int v = d * k + i;
        if (i > 0) yi -= 0.5 * (ext[v - 1].y() + ext[v].y()) - f[i - 1] * std::min(ext[v - 1].y(), ext[v].y());
        centre[v] = Eigen::Vector2d(xd + 0.02 * (2 * ub(9, v) - 1) * ext[v].x(), yi + 0.02 * (2 * ub(10, v) - 1) * ext[v].y());
      }
    }
    // The scene square: about the footprints of every view at heights +-relief/2, with a margin of 2% of the
    // largest extent; the layout shifted to its middle.
    Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
    double emax = 0;
    for (int v = 0; v < N; ++v) {
      m.cam[v] = make_synth_camera(affine, along[v], crossv[v], roll[v], kAltitude, sensor_focal(v, focal),
                                   Eigen::Vector3d(centre[v].x(), centre[v].y(), 0), n);
      emax = std::max(emax, ext[v].maxCoeff());
      for (int c = 0; c < 8; ++c) {
        Eigen::Vector3d o, dir;
        const double z = (c & 4) ? params.relief / 2 : -params.relief / 2;
        m.cam[v].ray((c & 1) ? n - 0.5 : -0.5, (c & 2) ? n - 0.5 : -0.5, z, o, dir);
        const Eigen::Vector3d X = o + ((o.z() - z) / -dir.z()) * dir;
        lo = lo.cwiseMin(X.head<2>());
        hi = hi.cwiseMax(X.head<2>());
      }
    }
    m.S = (hi - lo).maxCoeff() + 0.04 * emax;
    const Eigen::Vector2d shift = Eigen::Vector2d::Constant(m.S / 2) - 0.5 * (lo + hi);
    for (int v = 0; v < N; ++v)
      m.cam[v] = make_synth_camera(affine, along[v], crossv[v], roll[v], kAltitude, sensor_focal(v, focal),
                                   Eigen::Vector3d(centre[v].x() + shift.x(), centre[v].y() + shift.y(), 0), n);
  }
  // Terrain grid: covers what any pixel of any view can see at heights within +-relief (the clamp of the
  // terrain), plus the scene square.
  double x0 = 0, y0 = 0, x1 = m.S, y1 = m.S;
  const double zb = std::max(params.relief, 1.0);
  for (int v = 0; v < N; ++v)
    for (int k = 0; k < 4; ++k) {
      const double px = (k & 1) ? n + 1.0 : -2.0, py = (k & 2) ? n + 1.0 : -2.0;
      Eigen::Vector3d o, d;
      m.cam[v].ray(px, py, zb, o, d);
      for (double z : {zb, -zb}) {
        const double t = (o.z() - z) / -d.z();
        const Eigen::Vector3d X = o + t * d;
        x0 = std::min(x0, X.x());
        x1 = std::max(x1, X.x());
        y0 = std::min(y0, X.y());
        y1 = std::max(y1, X.y());
      }
    }
  const double spacing = 4 * params.gsd;
  m.terrain = SynthTerrain(params.seed, m.S, params.relief, spacing, x0 - 4 * spacing, y0 - 4 * spacing,
                           x1 + 4 * spacing, y1 + 4 * spacing);
  m.z_top = m.terrain.zmax() + 1.0;
  const double sun_az = (200 + 40 * u(60)) * kDeg, sun_el = 55 * kDeg;
  m.sun = Eigen::Vector3d(std::cos(sun_el) * std::cos(sun_az), std::cos(sun_el) * std::sin(sun_az), std::sin(sun_el));
  m.texture = SynthTexture(params.seed, params.gsd, sun_az, sun_el);
  if (params.buildings > 0 || params.trees > 0) {
    // Structures over the area of the terrain grid (what any view sees); ray origins above the highest.
    m.structures = SynthStructures(params.seed, params.buildings, params.trees, x0, y0, x1, y1, m.terrain);
    if (!m.structures.empty()) m.z_top = std::max(m.z_top, m.structures.zmax() + 1.0);
    // The sun of each date: date 1 the scene's; each later date its own stream (seeded), azimuth 25..60 deg
    // either side of the first, elevation 35..65 deg: the shadows move between dates.
    const uint64_t ss = synth::hash(params.seed, 0x5a7);
    m.date_sun.push_back(m.sun);
    for (int d = 1; d < m.p.dates; ++d) {
      const double side = synth::uniform(ss, d, 0) < 0.5 ? -1 : 1;
      const double az = sun_az + side * (25 + 35 * synth::uniform(ss, d, 1)) * kDeg, el = (35 + 30 * synth::uniform(ss, d, 2)) * kDeg;
      m.date_sun.emplace_back(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    }
  }
  if (params.blur > 0) {  // the same geometry and ground, seen by ideal sensors (sensor_rows blurs its rendering)
    SynthParams q = params;
    q.blur = 0;
    q.noise = 0;
    q.nodata = 0;
    m.sharp = std::make_unique<SynthScene>(q);
  }
}

const SynthTerrain& SynthScene::terrain_() const { return impl_->terrain; }
const SynthScene* SynthScene::sharp_() const { return impl_->sharp.get(); }
const SynthCamera& SynthScene::camera_(int view) const { return impl_->cam[static_cast<size_t>(view)]; }
double SynthScene::z_top_() const { return impl_->z_top; }
const SynthParams& SynthScene::params() const { return impl_->p; }
double SynthScene::scene_size() const { return impl_->S; }
double SynthScene::height(double X, double Y) const {
  const double z = impl_->terrain.height(X, Y);
  return impl_->structures.empty() ? z : std::max(z, impl_->structures.top(X, Y));
}
Eigen::Vector2d SynthScene::height_gradient(double X, double Y) const {
  Eigen::Vector2d g;
  const double z = impl_->terrain.height(X, Y, &g);
  if (!impl_->structures.empty()) {
    Eigen::Vector2d gs;
    if (impl_->structures.top(X, Y, &gs) > z) g = gs;
  }
  return g;
}
const SynthStructures& SynthScene::structures() const { return impl_->structures; }
bool SynthScene::has_structures() const { return !impl_->structures.empty(); }
Eigen::Vector3d SynthScene::sun(int view) const {
  const Impl& m = *impl_;
  if (m.p.date2 > 0 && view > 0) return synth_second_sun();
  const int d = date_of(view);
  return d < static_cast<int>(m.date_sun.size()) ? m.date_sun[static_cast<size_t>(d)] : m.sun;
}
bool SynthScene::in_shadow(int view, const Eigen::Vector3d& X, const Eigen::Vector3d& n) const {
  // from just off the surface (1 mm along its normal) towards the sun
  return impl_->structures.intersect(X + 1e-3 * n, sun(view), 0, std::numeric_limits<double>::infinity(), nullptr);
}
double SynthScene::surface_radiance(int view, const SynthSurface& s) const {
  const Eigen::Vector3d sn = sun(view);
  const double c = std::max(0.0, s.normal.dot(sn));
  const bool lit = c > 0 && !in_shadow(view, s.X, s.normal);
  const double shade = 0.3 + 0.7 * (lit ? c : 0.0);
  if (s.kind != SynthStructures::kTerrain) return impl_->structures.albedo(s.kind, s.id, s.X, impl_->p.gsd) * shade;
  if (!synth_has_conditions(impl_->p)) return impl_->texture.albedo(s.X.x(), s.X.y()) * shade;
  // the conditions' ground (their own shading), its direct part taken away in a cast shadow
  const Eigen::Vector2d g(-s.normal.x() / s.normal.z(), -s.normal.y() / s.normal.z());
  const double r = synth_condition_radiance(*this, view, s.X.x(), s.X.y(), g);
  return lit ? r : r * 0.3 / (0.3 + 0.7 * c);
}
double SynthScene::albedo(double X, double Y) const { return impl_->texture.albedo(X, Y); }
double SynthScene::radiance(double X, double Y) const {
  Eigen::Vector2d g;
  impl_->terrain.height(X, Y, &g);
  return radiance(X, Y, g);
}
namespace {
// Ambient + Lambert: the cosine of the sun's angle to the normal (-g, 1) / |(-g, 1)|, one division
// (sx, sy, sz: the sun's direction).
inline double shade(double sx, double sy, double sz, double gx, double gy) {
  const double cosine = (sz - gx * sx - gy * sy) / std::sqrt(gx * gx + gy * gy + 1);
  return 0.3 + 0.7 * std::max(0.0, cosine);
}
}  // namespace
double SynthScene::radiance(double X, double Y, const Eigen::Vector2d& g) const {
  const Eigen::Vector3d& s = impl_->sun;
  return impl_->texture.albedo(X, Y) * shade(s.x(), s.y(), s.z(), g.x(), g.y());
}
TPKIT_HOT void SynthScene::radiance_n(long n, const double* X, const double* Y, const double* gx, const double* gy, double* out) const {
  impl_->texture.albedo_n(n, X, Y, out);
  const double sx = impl_->sun.x(), sy = impl_->sun.y(), sz = impl_->sun.z();
  long i = 0;
#ifdef __SSE2__
  // shade() two points at a time, the same operations in the same order (the compiler does not vectorize
  // it: std::sqrt may set errno); max(c, 0) is std::max(0.0, c), nan and -0 included
  const __m128d vsx = _mm_set1_pd(sx), vsy = _mm_set1_pd(sy), vsz = _mm_set1_pd(sz), one = _mm_set1_pd(1.0);
  for (; i + 2 <= n; i += 2) {
    const __m128d vgx = _mm_loadu_pd(gx + i), vgy = _mm_loadu_pd(gy + i);
    const __m128d num = _mm_sub_pd(_mm_sub_pd(vsz, _mm_mul_pd(vgx, vsx)), _mm_mul_pd(vgy, vsy));
    const __m128d den = _mm_sqrt_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(vgx, vgx), _mm_mul_pd(vgy, vgy)), one));
    const __m128d cosine = _mm_max_pd(_mm_div_pd(num, den), _mm_setzero_pd());
    const __m128d sh = _mm_add_pd(_mm_set1_pd(0.3), _mm_mul_pd(_mm_set1_pd(0.7), cosine));
    _mm_storeu_pd(out + i, _mm_mul_pd(_mm_loadu_pd(out + i), sh));
  }
#endif
  for (; i < n; ++i) out[i] *= shade(sx, sy, sz, gx[i], gy[i]);
}
int SynthScene::views() const { return impl_->p.views; }
bool SynthScene::is_block() const { return synth_is_block(impl_->p); }
int SynthScene::date_of(int view) const { return view / synth_views_per_date(impl_->p); }
int SynthScene::index_in_date(int view) const { return view % synth_views_per_date(impl_->p); }
Eigen::Vector3d SynthScene::view_angles(int view) const { return impl_->angles.at(static_cast<size_t>(view)); }

std::array<Eigen::Vector2d, 4> SynthScene::footprint(int view, double Z) const {
  const double n = static_cast<double>(impl_->p.size);
  const double cx[4] = {-0.5, n - 0.5, n - 0.5, -0.5}, cy[4] = {-0.5, -0.5, n - 0.5, n - 0.5};
  std::array<Eigen::Vector2d, 4> out;
  for (int c = 0; c < 4; ++c) {
    Eigen::Vector3d o, d;
    impl_->cam.at(static_cast<size_t>(view)).ray(cx[c], cy[c], Z, o, d);
    out[c] = (o + ((o.z() - Z) / -d.z()) * d).head<2>();
  }
  return out;
}

double SynthScene::gain(int view) const { return impl_->gain[view]; }
double SynthScene::offset(int view) const { return impl_->offset[view]; }

Eigen::Vector2d SynthScene::project(int view, const Eigen::Vector3d& X) const { return impl_->cam[view].project(X); }
Eigen::Matrix<double, 3, 4> SynthScene::camera(int view) const { return impl_->cam[view].P; }

void SynthScene::ray(int view, double x, double y, Eigen::Vector3d& o, Eigen::Vector3d& d) const {
  impl_->cam[view].ray(x, y, impl_->z_top, o, d);
}

std::optional<Eigen::Vector3d> SynthScene::ground_point(int view, double x, double y) const {
  if (!impl_->structures.empty()) {
    const auto s = surface(view, x, y);
    if (!s) return std::nullopt;
    return s->X;
  }
  Eigen::Vector3d o, d;
  ray(view, x, y, o, d);
  const auto t = impl_->terrain.intersect(o, d);
  if (!t) return std::nullopt;
  return Eigen::Vector3d(o + *t * d);
}

std::optional<SynthSurface> SynthScene::surface(int view, double x, double y) const {
  Eigen::Vector3d o, d;
  ray(view, x, y, o, d);
  const auto t = impl_->terrain.intersect(o, d);
  SynthStructureHit h;
  SynthSurface s;
  if (impl_->structures.intersect(o, d, 0, t ? *t : std::numeric_limits<double>::infinity(), &h)) {
    s.X = o + h.t * d;
    s.normal = h.normal;
    s.kind = h.kind;
    s.id = h.id;
    return s;
  }
  if (!t) return std::nullopt;
  s.X = o + *t * d;
  Eigen::Vector2d g;
  impl_->terrain.height(s.X.x(), s.X.y(), &g);
  s.normal = Eigen::Vector3d(-g.x(), -g.y(), 1).normalized();
  return s;
}

bool SynthScene::visible(int view, const Eigen::Vector3d& X) const {
  const Eigen::Vector2d x = project(view, X);
  const double n = impl_->p.size;
  if (!(x.x() >= 0 && x.y() >= 0 && x.x() <= n - 1 && x.y() <= n - 1)) return false;
  Eigen::Vector3d o, d;
  ray(view, x.x(), x.y(), o, d);
  const auto t = impl_->terrain.intersect(o, d);
  // X lies on this ray at tX; hidden when the terrain (or a structure) is met clearly before it.
  const double tX = (X - o).dot(d);
  const double tol = 1e-6 * (1 + impl_->p.gsd);
  if (!impl_->structures.empty() && impl_->structures.intersect(o, d, 0, tX - tol, nullptr)) return false;
  if (!t) return true;
  return *t >= tX - tol;
}

SynthTruth synth_truth_points(const SynthScene& scene, long points) {
  const int N = scene.views();
  // The tri-stereo keeps points seen by all three views (as it always has); a block those seen by two or more.
  const int min_views = scene.is_block() ? 2 : N;
  SynthTruth truth;
  truth.xy.resize(points, 2 * N);
  truth.ground.resize(points, 3);
  if (points == 0) return truth;
  const double S = scene.scene_size();
  // Stratified: g x g cells over the scene square, visited in a seeded random order, one candidate per
  // cell per round, until `points` candidates visible in min_views views are found.
  const long g = std::max(1L, static_cast<long>(std::ceil(std::sqrt(points * 1.25))));
  std::vector<long> order(static_cast<size_t>(g * g));
  std::iota(order.begin(), order.end(), 0L);
  std::mt19937_64 rng(synth::hash(scene.params().seed, 0x77a));
  std::uniform_real_distribution<double> unif(0.0, 1.0);
  std::vector<char> seen(static_cast<size_t>(N));
  long found = 0;
  for (int round = 0; round < 50 && found < points; ++round) {
    std::shuffle(order.begin(), order.end(), rng);
    for (long c : order) {
      if (found == points) break;
      const double X = (c % g + unif(rng)) * S / g, Y = (c / g + unif(rng)) * S / g;
      const Eigen::Vector3d P(X, Y, scene.height(X, Y));
      int count = 0;
      for (int v = 0; v < N && count + (N - v) >= min_views; ++v) {
        seen[v] = scene.visible(v, P);
        count += seen[v];
      }
      if (count < min_views) continue;
      for (int v = 0; v < N; ++v)
        truth.xy.block<1, 2>(found, 2 * v) =
            seen[v] ? Eigen::RowVector2d(scene.project(v, P).transpose())
                    : Eigen::RowVector2d::Constant(std::numeric_limits<double>::quiet_NaN());
      truth.ground.row(found) = P.transpose();
      ++found;
    }
  }
  if (found < points)
    throw NumericalError("only " + std::to_string(found) + " of " + std::to_string(points) + " truth points are visible in " +
                         (scene.is_block() ? std::string("two views or more") : std::string("all three views")));
  return truth;
}

namespace {
// Area of a simple polygon (shoelace; either orientation).
double polygon_area(const std::vector<Eigen::Vector2d>& p) {
  double a = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d& q = p[i];
    const Eigen::Vector2d& r = p[(i + 1) % p.size()];
    a += q.x() * r.y() - r.x() * q.y();
  }
  return 0.5 * std::fabs(a);
}
// Sutherland-Hodgman: the convex polygon `subject` clipped by the convex polygon `clip` (any orientation).
std::vector<Eigen::Vector2d> clip_convex(std::vector<Eigen::Vector2d> subject, std::vector<Eigen::Vector2d> clip) {
  auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
    return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
  };
  double orient = 0;  // > 0: counter-clockwise
  for (size_t i = 0; i < clip.size(); ++i) orient += cross(clip[i], clip[(i + 1) % clip.size()], clip[(i + 2) % clip.size()]);
  if (orient < 0) std::reverse(clip.begin(), clip.end());
  for (size_t i = 0; i < clip.size() && !subject.empty(); ++i) {
    const Eigen::Vector2d a = clip[i], b = clip[(i + 1) % clip.size()];
    std::vector<Eigen::Vector2d> out;
    for (size_t j = 0; j < subject.size(); ++j) {
      const Eigen::Vector2d p = subject[j], q = subject[(j + 1) % subject.size()];
      const double cp = cross(a, b, p), cq = cross(a, b, q);
      if (cp >= 0) out.push_back(p);
      if ((cp >= 0) != (cq >= 0)) out.push_back(p + (cp / (cp - cq)) * (q - p));
    }
    subject = std::move(out);
  }
  return subject;
}
}  // namespace

double synth_footprint_overlap(const SynthScene& scene, int a, int b) {
  const auto fa = scene.footprint(a), fb = scene.footprint(b);
  const std::vector<Eigen::Vector2d> pa(fa.begin(), fa.end()), pb(fb.begin(), fb.end());
  const std::vector<Eigen::Vector2d> in = clip_convex(pa, pb);
  const double smaller = std::min(polygon_area(pa), polygon_area(pb));
  return in.size() < 3 || !(smaller > 0) ? 0.0 : polygon_area(in) / smaller;
}

std::vector<std::pair<int, int>> synth_neighbours(const SynthScene& scene) {
  std::vector<std::pair<int, int>> out;
  const int N = scene.views();
  if (!scene.is_block()) {
    for (int a = 0; a < N; ++a)
      for (int b = a + 1; b < N; ++b) out.emplace_back(a, b);
    return out;
  }
  const int k = synth_views_per_date(scene.params());
  for (int v = 0; v < N; ++v) {
    if (v % k + 1 < k) out.emplace_back(v, v + 1);  // next view of the date
    if (v + k < N) out.emplace_back(v, v + k);      // same view of the next date
  }
  std::sort(out.begin(), out.end());
  return out;
}

ImageBias synth_random_bias(const SynthScene& scene, int view, double px) {
  // Terms (rpc_bias.hpp): shift a0, b0 in +-px/2; a2, b2 (per row: drift) and a1, b1 (per column: affine)
  // each in +-(px/4) / (size - 1), so that each changes by at most px/4 across the image.
  const uint64_t s = synth::hash(scene.params().seed, 0xb1a5, view);
  auto r = [&](int k) { return 2 * synth::uniform(s, k) - 1; };
  const double span = static_cast<double>(std::max(1L, scene.params().size - 1));
  ImageBias b;
  b.a = {0.5 * px * r(0), 0.25 * px / span * r(1), 0.25 * px / span * r(2)};
  b.b = {0.5 * px * r(3), 0.25 * px / span * r(4), 0.25 * px / span * r(5)};
  return b;
}

}  // namespace tpkit
