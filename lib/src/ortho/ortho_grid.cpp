#include "tpkit/ortho/ortho_grid.hpp"

#include <proj.h>

#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "tpkit/core/error.hpp"
#include "tpkit/core/text_table.hpp"

namespace tpkit {

namespace {
constexpr double kDeg = M_PI / 180;
constexpr double kEarthRadius = 6371008.8;  // mean radius, m: for the default pixel size only

// A PROJ object of its own context, freed on every path out.
struct ProjObject {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* pj = nullptr;
  ProjObject() { proj_log_level(ctx, PJ_LOG_NONE); }
  ~ProjObject() {
    if (pj) proj_destroy(pj);
    proj_context_destroy(ctx);
  }
  ProjObject(const ProjObject&) = delete;
  ProjObject& operator=(const ProjObject&) = delete;
};

bool all_digits(const std::string& s) {
  return !s.empty() && s.size() < 10 && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}
}  // namespace

struct GridCrs::Impl {
  ProjObject proj;  // WGS 84 lon, lat -> the grid's x, y (normalized axis order)
  std::string name;
  std::mutex mutex;
};

GridCrs::GridCrs(int epsg, const std::string& what) : impl_(std::make_unique<Impl>()), epsg_(epsg) {
  ProjObject crs;
  const std::string code = "EPSG:" + std::to_string(epsg);
  crs.pj = proj_create(crs.ctx, code.c_str());
  if (!crs.pj) throw UsageError(what + " " + code + ": PROJ does not know this CRS");
  const PJ_TYPE type = proj_get_type(crs.pj);
  if (type != PJ_TYPE_PROJECTED_CRS)
    throw UsageError(what + " " + code + ": not a projected CRS (orthos are written on a grid in metres: utm, or a projected EPSG code)");
  PJ* cs = proj_crs_get_coordinate_system(crs.ctx, crs.pj);
  double factor = 0;
  if (cs) {
    const char* unit = nullptr;
    proj_cs_get_axis_info(crs.ctx, cs, 0, nullptr, nullptr, nullptr, &factor, &unit, nullptr, nullptr);
    proj_destroy(cs);
  }
  if (std::abs(factor - 1) > 1e-12) throw UsageError(what + " " + code + ": its unit is not the metre");
  const char* n = proj_get_name(crs.pj);
  impl_->name = code + (n ? std::string(" (") + n + ")" : std::string());
  Impl& d = *impl_;
  PJ* t = proj_create_crs_to_crs(d.proj.ctx, "EPSG:4326", code.c_str(), nullptr);
  if (t) {
    d.proj.pj = proj_normalize_for_visualization(d.proj.ctx, t);
    proj_destroy(t);
  }
  if (!d.proj.pj) throw UsageError(what + " " + code + ": PROJ has no transformation from WGS 84 to it");
}

GridCrs::~GridCrs() = default;

std::string GridCrs::name() const { return impl_->name; }

namespace {
void transform(PJ* pj, PJ_DIRECTION dir, std::size_t n, double* a, double* b) {
  proj_errno_reset(pj);
  proj_trans_generic(pj, dir, a, sizeof(double), n, b, sizeof(double), n, nullptr, 0, 0, nullptr, 0, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(a[i]) || !std::isfinite(b[i]) || a[i] == HUGE_VAL || b[i] == HUGE_VAL) a[i] = b[i] = NAN;
}
}  // namespace

void GridCrs::to_lonlat(std::size_t n, double* x, double* y) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  transform(impl_->proj.pj, PJ_INV, n, x, y);
}

void GridCrs::from_lonlat(std::size_t n, double* lon, double* lat) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  transform(impl_->proj.pj, PJ_FWD, n, lon, lat);
}

int resolve_ortho_crs(const std::string& spec, double lon, double lat) {
  if (spec == "utm") {
    const int zone = GeographicLib::UTMUPS::StandardZone(lat, lon);
    if (zone == GeographicLib::UTMUPS::UPS) throw UsageError("--crs utm: the first image lies in a polar (UPS) zone; name the CRS (EPSG:N)");
    return (lat >= 0 ? 32600 : 32700) + zone;
  }
  if (spec.size() > 5 && (spec.compare(0, 5, "EPSG:") == 0 || spec.compare(0, 5, "epsg:") == 0) && all_digits(spec.substr(5)))
    return std::stoi(spec.substr(5));
  ProjObject crs;
  crs.pj = proj_create(crs.ctx, spec.c_str());
  if (!crs.pj) throw UsageError("--crs '" + spec + "': neither utm, EPSG:N nor a CRS PROJ reads");
  // a CRS that PROJ can name by an EPSG code, the same CRS up to its name (a PROJ string's is "unknown": 70%
  // confidence) and the axis order: the GeoTIFF keys need a code
  int* confidence = nullptr;
  PJ_OBJ_LIST* found = proj_identify(crs.ctx, crs.pj, "EPSG", nullptr, &confidence);
  int code = 0;
  if (found) {
    for (int i = 0; i < proj_list_get_count(found) && code == 0; ++i) {
      if (confidence[i] < 70) continue;
      PJ* c = proj_list_get(crs.ctx, found, i);
      const char* id = c && proj_is_equivalent_to(c, crs.pj, PJ_COMP_EQUIVALENT_EXCEPT_AXIS_ORDER_GEOGCRS) ? proj_get_id_code(c, 0) : nullptr;
      if (id && all_digits(id)) code = std::stoi(id);
      if (c) proj_destroy(c);
    }
    proj_list_destroy(found);
    proj_int_list_destroy(confidence);
  }
  if (code == 0) throw UsageError("--crs '" + spec + "': PROJ finds no EPSG code for this CRS (the GeoTIFF keys name the CRS by its code): give EPSG:N");
  return code;
}

std::vector<Eigen::Vector2d> image_footprint(const OrthoSource& s, const HeightAt& height_at, int per_side) {
  std::vector<Eigen::Vector2d> pixels;
  const double w = s.width - 0.5, h = s.height - 0.5;
  for (int k = 0; k < per_side; ++k) {
    const double t = static_cast<double>(k) / per_side;
    pixels.emplace_back(-0.5 + t * (w + 0.5), -0.5);
    pixels.emplace_back(w, -0.5 + t * (h + 0.5));
    pixels.emplace_back(w - t * (w + 0.5), h);
    pixels.emplace_back(-0.5, h - t * (h + 0.5));
  }
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : pixels) {
    double z = s.model.height_off;
    Eigen::Vector2d ll = s.model.localize(p[0], p[1], z);
    // onto the surface: a few fixed-point steps (the height changes the ground point by a fraction of itself)
    for (int it = 0; it < 4 && height_at; ++it) {
      const double hz = height_at(ll[0], ll[1]);
      if (!std::isfinite(hz) || std::abs(hz - z) < 0.01) break;
      z = hz;
      ll = s.model.localize(p[0], p[1], z);
    }
    out.push_back(ll);
  }
  return out;
}

double ground_sampling(const OrthoSource& s, const HeightAt& height_at) {
  const double cx = (s.width - 1) / 2.0, cy = (s.height - 1) / 2.0;
  double z = s.model.height_off;
  if (height_at) {
    const Eigen::Vector2d ll = s.model.localize(cx, cy, z);
    const double hz = height_at(ll[0], ll[1]);
    if (std::isfinite(hz)) z = hz;
  }
  const Eigen::Vector2d a = s.model.localize(cx, cy, z), b = s.model.localize(cx + 1, cy, z), c = s.model.localize(cx, cy + 1, z);
  // local east / north metres per degree on a sphere: a default pixel size, not a measurement
  const double ex = kEarthRadius * kDeg * std::cos(a[1] * kDeg), ny = kEarthRadius * kDeg;
  const Eigen::Vector2d u((b[0] - a[0]) * ex, (b[1] - a[1]) * ny), v((c[0] - a[0]) * ex, (c[1] - a[1]) * ny);
  return std::sqrt(std::abs(u[0] * v[1] - u[1] * v[0]));
}

OrthoGrid grid_covering(int epsg, double gsd, const std::vector<Eigen::Vector2d>& points) {
  double xmin = std::numeric_limits<double>::infinity(), ymin = xmin, xmax = -xmin, ymax = -xmin;
  for (const auto& p : points) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1])) continue;
    xmin = std::min(xmin, p[0]);
    xmax = std::max(xmax, p[0]);
    ymin = std::min(ymin, p[1]);
    ymax = std::max(ymax, p[1]);
  }
  if (!(xmin <= xmax && ymin <= ymax)) throw NumericalError("the images' footprints have no point in the output CRS");
  OrthoGrid g;
  g.epsg = epsg;
  g.gsd = gsd;
  g.x0 = std::floor(xmin / gsd) * gsd;
  g.y0 = std::ceil(ymax / gsd) * gsd;
  const double w = std::max(1.0, std::round((std::ceil(xmax / gsd) * gsd - g.x0) / gsd));
  const double h = std::max(1.0, std::round((g.y0 - std::floor(ymin / gsd) * gsd) / gsd));
  if (!(w * h <= kMaxOrthoPixels))
    throw UsageError("the footprints' union is " + format_figure(w) + " x " + format_figure(h) + " pixels of " + format_number(gsd) +
                     " m: above 2^34 pixels (a --gsd typo?)");
  g.width = static_cast<long>(w);
  g.height = static_cast<long>(h);
  return g;
}

OrthoGrid grid_of_bounds(int epsg, double gsd, double xmin, double ymin, double xmax, double ymax) {
  if (!(xmin < xmax && ymin < ymax)) throw UsageError("--bounds XMIN YMIN XMAX YMAX: need XMIN < XMAX and YMIN < YMAX");
  OrthoGrid g;
  g.epsg = epsg;
  g.gsd = gsd;
  g.x0 = xmin;
  g.y0 = ymax;
  const double w = std::ceil((xmax - xmin) / gsd - 1e-9), h = std::ceil((ymax - ymin) / gsd - 1e-9);
  if (!(w * h <= kMaxOrthoPixels)) throw UsageError("--bounds: " + format_figure(w) + " x " + format_figure(h) + " pixels of " + format_number(gsd) + " m: above 2^34 pixels");
  g.width = static_cast<long>(w);
  g.height = static_cast<long>(h);
  return g;
}

void check_grid(const OrthoGrid& g, const std::string& what) {
  if (!(g.gsd > 0) || g.width < 1 || g.height < 1) throw InputError(what + ": an empty grid");
  if (static_cast<double>(g.width) * static_cast<double>(g.height) > kMaxOrthoPixels)
    throw UsageError(what + ": " + std::to_string(g.width) + " x " + std::to_string(g.height) + " pixels of " + format_number(g.gsd) +
                     " m: above 2^34 pixels (a --gsd or --bounds typo?)");
}

}  // namespace tpkit
