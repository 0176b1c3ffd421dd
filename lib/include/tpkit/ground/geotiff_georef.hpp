// Where a GeoTIFF's pixels lie: its size, its CRS and the affine map from pixel to model coordinates, read
// from the GeoTIFF keys and tags (libgeotiff), and the map of its pixels to WGS 84 lon, lat (PROJ). For
// rasters that are not DEMs (orthoimages of any band count and sample type); a DEM is read by ReferenceDem.
//
// Conventions: pixel (c, r), c = column, r = row, (0, 0) the centre of the top-left pixel; model
// x = a[0] + a[1] c + a[2] r, y = a[3] + a[4] c + a[5] r in the CRS's units (ModelTiepoint + ModelPixelScale
// or ModelTransformation; PixelIsArea puts the tie point at the pixel's corner, PixelIsPoint at its centre).
// lon, lat in degrees (WGS 84), east and north.
#pragma once
#include <array>
#include <memory>
#include <string>

namespace tpkit {

struct GeoTiffGeoref {
  std::string path;
  long width = 0, height = 0;
  std::string crs;          // "EPSG:N", or a PROJ string for a user-defined CRS
  bool geographic = false;  // lon, lat model coordinates
  std::array<double, 6> a{0, 1, 0, 0, 0, -1};  // pixel centre (c, r) -> model (x, y), see above
};

// InputError naming `path` for a file that is not a TIFF, or has no GeoTIFF keys, no georeferencing (tie point
// and pixel scale, or transformation matrix), a degenerate one (pixel size 0) or no CRS libgeotiff can describe.
GeoTiffGeoref read_geotiff_georef(const std::string& path);

// Pixel (c, r) of a georeferenced raster to WGS 84 lon, lat. Not thread-safe (one PROJ context per object).
class GeorefToLonLat {
 public:
  // InputError naming the raster's path when PROJ does not know its CRS.
  explicit GeorefToLonLat(const GeoTiffGeoref& g);
  ~GeorefToLonLat();
  GeorefToLonLat(const GeorefToLonLat&) = delete;
  GeorefToLonLat& operator=(const GeorefToLonLat&) = delete;
  // False where PROJ cannot transform the point.
  bool operator()(double c, double r, double& lon, double& lat) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tpkit
