// Orthorectification against closed form: an RPC model that is affine in (lon, lat, h) by construction (a
// pixel's ground point known exactly), an image whose value is an affine function of the pixel (reproduced
// exactly by bilinear and by bicubic resampling), so that every output pixel's value is known: its centre
// (grid convention) -> lon, lat (PROJ, in the test) -> height (flat, or a tilted plane DEM) -> pixel ->
// value. Also the GeoTIFF's grid read back, nodata off the image, and the default grid from footprints.
#include <gtest/gtest.h>
#include <proj.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/ground/reference_dem.hpp"
#include "tpkit/ortho/ortho_geotiff.hpp"
#include "tpkit/ortho/ortho_grid.hpp"
#include "tpkit/ortho/orthorectify.hpp"
#include "affine_rpc.hpp"

using namespace tpkit;

namespace {

std::string scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("tpkit_ortho_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

// affine_rpc.hpp's model centred at 5.4 E
RpcModel affine_model() { return affine_rpc(5.4); }
Eigen::Vector2d affine_pixel(double lon, double lat, double h) {
  return {200 + 200 * (lon - 5.4) / 0.002 + 20 * (h - 100) / 200, 200 - 200 * (lat - 43.3) / 0.002};
}
double image_value(double x, double y) { return 1000 + 20 * x + 7 * y; }

std::string write_affine_image() {
  const std::string path = scratch("affine.tif");
  std::vector<uint16_t> v(400 * 400);
  for (long y = 0; y < 400; ++y)
    for (long x = 0; x < 400; ++x) v[static_cast<size_t>(y * 400 + x)] = static_cast<uint16_t>(image_value(x, y));
  write_image_u16(path, 400, 400, v);
  return path;
}

struct Utm31 {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* raw = proj_create_crs_to_crs(ctx, "EPSG:4326", "EPSG:32631", nullptr);
  PJ* pj = proj_normalize_for_visualization(ctx, raw);
  ~Utm31() {
    proj_destroy(pj);
    proj_destroy(raw);
    proj_context_destroy(ctx);
  }
  Eigen::Vector2d lonlat(double e, double n) const {
    const PJ_COORD q = proj_trans(pj, PJ_INV, proj_coord(e, n, 0, 0));
    return {q.lp.lam, q.lp.phi};
  }
};

// The grid of 1 m pixels around the image (UTM 31N), and a tilted plane of heights over it.
OrthoGrid test_grid() { return grid_of_bounds(32631, 1.0, 694400, 4796600, 694950, 4797250); }
double plane(double e, double n) { return 60 + 0.2 * (e - 694400) - 0.1 * (n - 4796600); }

// Every valid output pixel against the closed form; returns the number checked, the largest error.
void check_against_closed_form(const std::string& ortho, const OrthoGrid& g, bool dem, long& checked, long& nodata, double& worst) {
  const Utm31 utm;
  const Raster r = read_band(ortho, 0);
  checked = nodata = 0;
  worst = 0;
  for (long row = 0; row < g.height; row += 3)
    for (long col = 0; col < g.width; col += 3) {
      const double e = g.x0 + (col + 0.5) * g.gsd, n = g.y0 - (row + 0.5) * g.gsd;
      const Eigen::Vector2d ll = utm.lonlat(e, n);
      const Eigen::Vector2d p = affine_pixel(ll[0], ll[1], dem ? plane(e, n) : 150.0);
      const float got = r.at(col, row);
      // well inside the image: known; well outside: nodata; the rim between is not checked
      if (p[0] > 2 && p[0] < 397 && p[1] > 2 && p[1] < 397) {
        worst = std::max(worst, std::abs(got - image_value(p[0], p[1])));
        ++checked;
      } else if (p[0] < -1 || p[0] > 400 || p[1] < -1 || p[1] > 400) {
        EXPECT_EQ(got, 0) << col << " " << row;
        ++nodata;
      }
    }
}

}  // namespace

TEST(Orthorectify, FlatHeightGivesTheKnownPixel) {
  const std::string image = write_affine_image(), out = scratch("flat.ortho.tif");
  const OrthoGrid g = test_grid();
  const GridCrs crs(g.epsg);
  OrthoSurface s;
  s.height = 150;
  OrthoOptions o;
  o.threads = 2;
  const OrthoStats st = orthorectify(image, affine_model(), g, crs, s, o, out);
  EXPECT_GT(st.valid, 100000);
  long checked, nodata;
  double worst;
  check_against_closed_form(out, g, false, checked, nodata, worst);
  EXPECT_GT(checked, 10000);
  EXPECT_GT(nodata, 1000);
  EXPECT_LE(worst, 0.5 + 1e-3);  // the value rounded to uint16, nothing else
  // the file says its grid
  const OrthoFileInfo info = read_ortho_info(out);
  EXPECT_EQ(info.grid.epsg, 32631);
  EXPECT_DOUBLE_EQ(info.grid.x0, 694400);
  EXPECT_DOUBLE_EQ(info.grid.y0, 4797250);
  EXPECT_DOUBLE_EQ(info.grid.gsd, 1.0);
  EXPECT_EQ(info.grid.width, 550);
  EXPECT_EQ(info.grid.height, 650);
  EXPECT_TRUE(info.has_nodata);
  EXPECT_EQ(image_info(out).format, "uint16");
}

TEST(Orthorectify, DemHeightsAndBicubic) {
  const std::string image = write_affine_image(), out = scratch("dem.ortho.tif"), demf = scratch("plane.tif");
  // the plane on a 5 m UTM grid (bilinear reproduces it exactly), wider than the grid
  DemRaster d;
  d.epsg = 32631;
  d.x0 = 694300;
  d.y0 = 4797350;
  d.dx = d.dy = 5;
  d.width = 160;
  d.height = 180;
  for (long r = 0; r < d.height; ++r)
    for (long c = 0; c < d.width; ++c) d.data.push_back(static_cast<float>(plane(d.x0 + c * d.dx, d.y0 - r * d.dy)));
  write_reference_dem(demf, d);
  const ReferenceDem dem(demf);
  const OrthoGrid g = test_grid();
  const GridCrs crs(g.epsg);
  OrthoSurface s;
  s.dem = &dem;
  OrthoOptions o;
  o.threads = 2;
  o.resampling = Resampling::bicubic;
  orthorectify(image, affine_model(), g, crs, s, o, out);
  long checked, nodata;
  double worst;
  check_against_closed_form(out, g, true, checked, nodata, worst);
  EXPECT_GT(checked, 10000);
  EXPECT_LE(worst, 0.5 + 0.01);  // float32 plane heights: 1e-5 m, 1e-6 px
}

TEST(Orthorectify, OffTheDemIsNodata) {
  const std::string image = write_affine_image(), out = scratch("small-dem.ortho.tif"), demf = scratch("small.tif");
  DemRaster d;
  d.epsg = 32631;
  d.x0 = 694620;
  d.y0 = 4796980;
  d.dx = d.dy = 5;
  d.width = d.height = 21;  // 100 x 100 m
  d.data.assign(441, 150.0f);
  write_reference_dem(demf, d);
  const ReferenceDem dem(demf);
  const OrthoGrid g = test_grid();
  const GridCrs crs(g.epsg);
  OrthoSurface s;
  s.dem = &dem;
  const OrthoStats st = orthorectify(image, affine_model(), g, crs, s, OrthoOptions{}, out);
  EXPECT_LE(st.valid, 101 * 101);
  EXPECT_GE(st.valid, 99 * 99);
  EXPECT_GT(st.no_height, 100000);
}

TEST(OrthoGrid, CrsNames) {
  EXPECT_EQ(resolve_ortho_crs("utm", 5.4, 43.3), 32631);
  EXPECT_EQ(resolve_ortho_crs("utm", -81.7, 30.3), 32617);
  EXPECT_EQ(resolve_ortho_crs("utm", 151.2, -33.9), 32756);
  EXPECT_EQ(resolve_ortho_crs("EPSG:2154", 0, 0), 2154);
  EXPECT_EQ(resolve_ortho_crs("+proj=utm +zone=17 +datum=WGS84 +units=m +no_defs +type=crs", 0, 0), 32617);
  EXPECT_THROW(resolve_ortho_crs("nonsense", 0, 0), UsageError);
  EXPECT_THROW(GridCrs(4326), UsageError);  // geographic: not a grid in metres
}

TEST(OrthoGrid, FootprintAndSamplingOfAKnownModel) {
  OrthoSource s{affine_model(), 400, 400};
  // flat at height_off: the corners of the image's area are lon_off -+ 0.002 * (200.5 / 200), likewise lat
  const std::vector<Eigen::Vector2d> f = image_footprint(s, [](double, double) { return 100.0; }, 4);
  ASSERT_EQ(f.size(), 16u);
  double lon0 = 1e9, lon1 = -1e9, lat0 = 1e9, lat1 = -1e9;
  for (const auto& p : f) {
    lon0 = std::min(lon0, p[0]);
    lon1 = std::max(lon1, p[0]);
    lat0 = std::min(lat0, p[1]);
    lat1 = std::max(lat1, p[1]);
  }
  EXPECT_NEAR(lon0, 5.4 - 0.002 * 200.5 / 200, 1e-10);
  EXPECT_NEAR(lon1, 5.4 + 0.002 * 199.5 / 200, 1e-10);
  EXPECT_NEAR(lat1, 43.3 + 0.002 * 200.5 / 200, 1e-10);
  EXPECT_NEAR(lat0, 43.3 - 0.002 * 199.5 / 200, 1e-10);
  // one pixel: 1e-5 deg of lon (0.81 m at 43.3 N) by 1e-5 deg of lat (1.11 m): about 0.95 m
  const double gsd = ground_sampling(s, nullptr);
  EXPECT_NEAR(gsd, std::sqrt(1e-5 * 111195 * std::cos(43.3 * M_PI / 180) * 1e-5 * 111195), 0.01);
  // the grid covering them: corners on multiples of the pixel size, every point inside
  const GridCrs crs(32631);
  std::vector<double> x, y;
  for (const auto& p : f) {
    x.push_back(p[0]);
    y.push_back(p[1]);
  }
  crs.from_lonlat(x.size(), x.data(), y.data());
  std::vector<Eigen::Vector2d> pts;
  for (size_t i = 0; i < x.size(); ++i) pts.emplace_back(x[i], y[i]);
  const OrthoGrid g = grid_covering(32631, 0.5, pts);
  EXPECT_DOUBLE_EQ(std::fmod(g.x0, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(std::fmod(g.y0, 0.5), 0.0);
  for (const auto& p : pts) {
    EXPECT_GE(p[0], g.x0);
    EXPECT_LE(p[0], g.x1());
    EXPECT_LE(p[1], g.y0);
    EXPECT_GE(p[1], g.y1());
  }
  EXPECT_LT(g.x1() - *std::max_element(x.begin(), x.end()), 0.5);
  EXPECT_LT(*std::min_element(x.begin(), x.end()) - g.x0, 0.5);
}
