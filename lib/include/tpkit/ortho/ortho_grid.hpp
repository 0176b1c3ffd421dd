// The output grid of orthoimages: a projected CRS (PROJ, named by its EPSG code so that GeoTIFF keys can
// say it), square pixels of `gsd` metres, and the extent; by default the union of the images' footprints, so
// that every ortho of a run lies on one grid and they overlay pixel for pixel.
//
// Conventions: grid pixel (c, r) (c = column, r = row, (0, 0) the centre of the top-left pixel) has its centre
// at model (x0 + (c + 0.5) gsd, y0 - (r + 0.5) gsd): (x0, y0) is the top-left CORNER of the grid (GeoTIFF
// PixelIsArea, GDAL's geotransform x0, gsd, 0, y0, 0, -gsd). Ground: lon, lat in degrees (WGS 84), heights
// in metres above the WGS 84 ellipsoid (as RPC models take them). Image pixels as tpkit's (rpc_model.hpp).
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

struct OrthoGrid {
  int epsg = 0;             // the CRS: a projected CRS in metres
  double x0 = 0, y0 = 0;    // model coordinates of the grid's top-left corner
  double gsd = 0;           // pixel size, metres (rows run towards -y)
  long width = 0, height = 0;
  double x1() const { return x0 + width * gsd; }
  double y1() const { return y0 - height * gsd; }
};

// The grid's CRS to and from WGS 84 (lon, lat degrees, in that order), through PROJ. Thread-safe (one lock
// per batch: transform many points per call).
class GridCrs {
 public:
  // UsageError naming `what` when PROJ does not know the code or the CRS is not projected in metres.
  explicit GridCrs(int epsg, const std::string& what = "--crs");
  ~GridCrs();
  GridCrs(const GridCrs&) = delete;
  GridCrs& operator=(const GridCrs&) = delete;
  int epsg() const { return epsg_; }
  std::string name() const;  // e.g. "EPSG:32631 (WGS 84 / UTM zone 31N)"
  // In place: x, y (model coordinates) -> lon, lat; a point PROJ cannot transform becomes NaN.
  void to_lonlat(std::size_t n, double* x, double* y) const;
  // In place: lon, lat -> x, y.
  void from_lonlat(std::size_t n, double* lon, double* lat) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int epsg_ = 0;
};

// The EPSG code of --crs `spec`: "utm" (the UTM zone, WGS 84, of (lon, lat)), "EPSG:N", or a PROJ string or
// WKT that PROJ identifies with an EPSG CRS (GeoTIFF keys name the CRS by its code). UsageError otherwise.
int resolve_ortho_crs(const std::string& spec, double lon, double lat);

// An image and its model, as the grid sees them.
struct OrthoSource {
  RpcModel model;
  long width = 0, height = 0;
};
// Height above the ellipsoid at (lon, lat); NaN where unknown (off the DEM).
using HeightAt = std::function<double(double lon, double lat)>;

// The image's outline on the ground: 4 x `per_side` points along its edges (pixel corners, -0.5 and
// width - 0.5), each localized at the height found there (height_at, iterated from the model's
// height_off; height_off where unknown). Rows: lon, lat.
std::vector<Eigen::Vector2d> image_footprint(const OrthoSource& s, const HeightAt& height_at, int per_side = 8);

// The image's ground sampling at its centre, metres: the square root of the ground area of one pixel
// there (localized at height_at, else height_off).
double ground_sampling(const OrthoSource& s, const HeightAt& height_at);

// The grid covering every point (x, y in the grid's CRS) with pixels of `gsd` m, its corners on multiples of
// gsd (grids of the same CRS and gsd made from other images then share their pixels).
OrthoGrid grid_covering(int epsg, double gsd, const std::vector<Eigen::Vector2d>& points);
// The grid of the bounds XMIN YMIN XMAX YMAX (model coordinates): x0 = XMIN, y0 = YMAX, the size rounded up.
OrthoGrid grid_of_bounds(int epsg, double gsd, double xmin, double ymin, double xmax, double ymax);

// The largest grid written: 2^34 pixels (a 130000 x 130000 ortho); beyond it a typo in --gsd or --bounds.
constexpr double kMaxOrthoPixels = 17179869184.0;
// InputError / UsageError (naming `what`) for an empty grid or one above kMaxOrthoPixels.
void check_grid(const OrthoGrid& g, const std::string& what);

}  // namespace tpkit
