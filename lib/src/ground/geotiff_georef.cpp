#include "tpkit/ground/geotiff_georef.hpp"

#include <geotiff/geo_normalize.h>
#include <geotiff/geotiff.h>
#include <geotiff/geovalues.h>
#include <geotiff/xtiffio.h>
#include <proj.h>
#include <tiffio.h>

#include <cmath>

#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "geotiff_tags.hpp"

namespace tpkit {

namespace {

// "EPSG:N" from the model type's code key, else libgeotiff's PROJ string of a user-defined CRS.
std::string crs_of(GTIF* gtif, const std::string& path, bool& geographic) {
  unsigned short model = 0, code = 0;
  GTIFKeyGetSHORT(gtif, GTModelTypeGeoKey, &model, 0, 1);
  geographic = model == ModelTypeGeographic;
  if (model == ModelTypeProjected && GTIFKeyGetSHORT(gtif, ProjectedCSTypeGeoKey, &code, 0, 1) && code != KvUserDefined)
    return "EPSG:" + std::to_string(code);
  if (model == ModelTypeGeographic && GTIFKeyGetSHORT(gtif, GeographicTypeGeoKey, &code, 0, 1) && code != KvUserDefined)
    return "EPSG:" + std::to_string(code);
  if (model != ModelTypeProjected && model != ModelTypeGeographic)
    throw InputError(path, 0, "no CRS in the GeoTIFF keys (GTModelTypeGeoKey " + std::to_string(model) + ": neither projected nor geographic)");
  std::string def;
  GTIFDefn defn;
  if (GTIFGetDefn(gtif, &defn))
    if (char* p4 = GTIFGetProj4Defn(&defn)) {
      def = p4;
      GTIFFreeMemory(p4);
    }
  if (def.empty()) throw InputError(path, 0, "a user-defined CRS that libgeotiff cannot describe");
  return def;
}

}  // namespace

std::array<double, 6> geotiff_pixel_to_model(TIFF* tif, GTIF* gtif, const std::string& path) {
  unsigned short raster_type = RasterPixelIsArea;
  GTIFKeyGetSHORT(gtif, GTRasterTypeGeoKey, &raster_type, 0, 1);
  const double centre = raster_type == RasterPixelIsPoint ? 0.0 : 0.5;  // raster space of pixel centre (0, 0)
  uint16_t n_scale = 0, n_tie = 0, n_matrix = 0;
  double *scale = nullptr, *tie = nullptr, *matrix = nullptr;
  TIFFGetField(tif, TIFFTAG_GEOPIXELSCALE, &n_scale, &scale);
  TIFFGetField(tif, TIFFTAG_GEOTIEPOINTS, &n_tie, &tie);
  TIFFGetField(tif, TIFFTAG_GEOTRANSMATRIX, &n_matrix, &matrix);
  double m[6];  // model = m * (i, j, 1) in raster space
  if (n_matrix >= 16 && matrix) {
    m[0] = matrix[3], m[1] = matrix[0], m[2] = matrix[1];
    m[3] = matrix[7], m[4] = matrix[4], m[5] = matrix[5];
  } else if (n_scale >= 2 && scale && n_tie >= 6 && tie) {
    if (n_tie > 6) throw InputError(path, 0, "several GeoTIFF tie points without a transformation (not a regular grid)");
    m[1] = scale[0], m[2] = 0, m[0] = tie[3] - tie[0] * scale[0];
    m[4] = 0, m[5] = -scale[1], m[3] = tie[4] + tie[1] * scale[1];
  } else {
    throw InputError(path, 0, "no georeferencing (no GeoTIFF ModelTiepoint + ModelPixelScale nor ModelTransformation)");
  }
  std::array<double, 6> a{m[0] + centre * (m[1] + m[2]), m[1], m[2], m[3] + centre * (m[4] + m[5]), m[4], m[5]};
  const double det = a[1] * a[5] - a[2] * a[4];
  if (!(std::fabs(det) > 0) || !std::isfinite(det)) throw InputError(path, 0, "degenerate georeferencing (pixel size 0)");
  return a;
}

GeoTiffGeoref read_geotiff_georef(const std::string& path) {
  check_input_file(path, InputKind::image);  // libtiff's open blocks on a FIFO for ever
  TIFFSetErrorHandler(nullptr);
  TIFFSetWarningHandler(nullptr);
  TIFF* tif = XTIFFOpen(path.c_str(), "r");
  if (!tif) throw InputError(path, 0, "cannot be read as a TIFF");
  GTIF* gtif = GTIFNew(tif);
  GeoTiffGeoref g;
  g.path = path;
  try {
    if (!gtif) throw InputError(path, 0, "no GeoTIFF keys (no georeferencing)");
    uint32_t w = 0, h = 0;
    TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &w);
    TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &h);
    g.width = w, g.height = h;
    g.a = geotiff_pixel_to_model(tif, gtif, path);
    g.crs = crs_of(gtif, path, g.geographic);
  } catch (...) {
    if (gtif) GTIFFree(gtif);
    XTIFFClose(tif);
    throw;
  }
  GTIFFree(gtif);
  XTIFFClose(tif);
  return g;
}

struct GeorefToLonLat::Impl {
  GeoTiffGeoref g;
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* pj = nullptr;  // model x, y -> lon, lat (axis order normalized)
  ~Impl() {
    if (pj) proj_destroy(pj);
    proj_context_destroy(ctx);
  }
};

GeorefToLonLat::GeorefToLonLat(const GeoTiffGeoref& g) : impl_(std::make_unique<Impl>()) {
  impl_->g = g;
  proj_log_level(impl_->ctx, PJ_LOG_NONE);
  const std::string def = g.crs[0] == '+' ? g.crs + " +type=crs" : g.crs;
  PJ* raw = proj_create_crs_to_crs(impl_->ctx, def.c_str(), "EPSG:4326", nullptr);
  if (!raw) throw InputError(g.path, 0, "unknown CRS " + g.crs);
  impl_->pj = proj_normalize_for_visualization(impl_->ctx, raw);
  proj_destroy(raw);
  if (!impl_->pj) throw InputError(g.path, 0, "CRS " + g.crs + ": PROJ cannot normalize its axis order");
}

GeorefToLonLat::~GeorefToLonLat() = default;

bool GeorefToLonLat::operator()(double c, double r, double& lon, double& lat) const {
  const auto& a = impl_->g.a;
  PJ_COORD in = proj_coord(a[0] + a[1] * c + a[2] * r, a[3] + a[4] * c + a[5] * r, 0, 0);
  PJ_COORD out = proj_trans(impl_->pj, PJ_FWD, in);
  lon = out.xy.x, lat = out.xy.y;
  return std::isfinite(lon) && std::isfinite(lat) && std::fabs(lon) <= 360 && std::fabs(lat) <= 90;
}

}  // namespace tpkit
