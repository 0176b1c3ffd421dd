// A reference DEM: a single-band GeoTIFF in any projected or geographic CRS (georeferencing and CRS from its
// GeoTIFF keys, libgeotiff), heights above the ellipsoid or a geoid, sampled at WGS 84 (lon, lat) by bilinear
// interpolation between pixel centres, returning heights above the WGS 84 ellipsoid. Tiles or strips are read
// on demand into a bounded cache, so a DEM larger than memory can be used.
//
// Conventions: lon, lat in degrees (WGS 84, EPSG:4326 / EPSG:4979), heights in metres. A DEM's pixel (c, r)
// (c = column, r = row, 0 = centre of the top-left pixel) lies at model (x, y) by the GeoTIFF's ModelTiepoint +
// ModelPixelScale or ModelTransformation, PixelIsArea (tie point at the pixel's corner) or PixelIsPoint (at its
// centre). Vertical datum: "ellipsoid" (heights above the ellipsoid of the DEM's CRS, taken as WGS 84's),
// "egm96" (PROJ grid egm96_15.gtx, Debian proj-data), "egm2008" (PROJ grid egm08_25.gtx) or the path of a
// vertical grid PROJ reads (GTX, GeoTIFF): h_ellipsoid = H + N(lon, lat), N the grid's geoid undulation.
// Unless the caller names one, the datum is the GeoTIFF's vertical keys' (VerticalCSTypeGeoKey 5773 EGM96
// height, 3855 EGM2008 height, 5030 WGS 84 ellipsoidal; else VerticalDatumGeoKey 5171 EGM96, 1027 EGM2008, 6326
// WGS 84), ellipsoidal when the keys give none; a named datum that disagrees with the keys is refused (keys of a
// vertical CRS tpkit does not know: the caller must name its grid). Heights in the VerticalUnitsGeoKey's unit
// (feet, US survey feet...) are converted to metres.
// Nodata (GDAL_NODATA tag 42113, compared in the band's sample type as GDAL does: "-3.4e+38" is the float32
// -3.4e38), NaN and cells outside the DEM are unknown: a sample needs the 4 cells around it known.
// Memory: a tile, or a strip read whole, takes at most kMaxDemBlockBytes decoded; a larger strip is read row
// by row (libtiff decodes a strip's rows in order: sampling it out of order decodes it again from its start,
// slow for a big compressed strip but bounded), a larger tile is refused (libtiff decodes a tile only whole).
#pragma once
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace tpkit {

// Decoded bytes a DEM tile (or a strip read whole) may take: 64 MiB, e.g. 4096 x 4096 float32 cells.
constexpr std::size_t kMaxDemBlockBytes = std::size_t(64) << 20;

// A geoid model (or none): N(lon, lat) in metres, h_ellipsoid = H_geoid + N. `datum`: ellipsoid|egm96|egm2008|
// a grid's file name or path. InputError naming `what` (the option or file it is for) when the grid is missing,
// or when `datum` is not one of these: the grid goes into a PROJ definition, so PROJ's optional-grid '@', a
// list (','), spaces or '+' parameters are refused rather than pasted in.
class VerticalDatum {
 public:
  explicit VerticalDatum(const std::string& datum, const std::string& what = "--dem-datum");
  ~VerticalDatum();
  VerticalDatum(const VerticalDatum&) = delete;
  VerticalDatum& operator=(const VerticalDatum&) = delete;
  bool is_ellipsoid() const;
  const std::string& name() const { return name_; }
  // N at (lon, lat), metres; NaN where the grid has no value.
  double undulation(double lon, double lat) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string name_;
};

struct ReferenceDemOptions {
  std::string datum;                      // ellipsoid|egm96|egm2008|GRID; empty: the GeoTIFF's vertical keys
  std::size_t cache_bytes = 256u << 20;   // tiles (strips) kept in memory at most
};

class ReferenceDem {
 public:
  // InputError naming `path` for a file that is not a single-band GeoTIFF, has no georeferencing, an unknown
  // CRS, a tile above kMaxDemBlockBytes, a datum that disagrees with its vertical keys, or a datum grid that is
  // missing.
  explicit ReferenceDem(const std::string& path, const ReferenceDemOptions& options = {});
  ~ReferenceDem();
  ReferenceDem(const ReferenceDem&) = delete;
  ReferenceDem& operator=(const ReferenceDem&) = delete;

  // Height above the WGS 84 ellipsoid at (lon, lat) and, when grad is not null, its derivatives in metres per
  // degree of lon and of lat (the geoid's slope neglected: below 1e-4). False where unknown. Thread-safe.
  bool height(double lon, double lat, double& h, double* grad = nullptr) const;
  // The same for n points at once (one lock, one batch transformation: for rasters, where a call per point
  // costs more than the sampling): h[i] above the WGS 84 ellipsoid, NaN where unknown. Thread-safe.
  void heights(std::size_t n, const double* lon, const double* lat, double* h) const;
  // Slope (degrees from horizontal) and aspect (degrees clockwise from north, of the downhill direction) at
  // (lon, lat) from the bilinear surface; false where unknown.
  bool slope_aspect(double lon, double lat, double& slope_deg, double& aspect_deg) const;

  const std::string& path() const;
  std::string crs() const;             // e.g. "EPSG:32631"
  const std::string& datum() const;    // the vertical datum used: ellipsoid|egm96|egm2008|GRID
  double vertical_unit_m() const;      // metres per unit of the stored heights (1 unless the keys say otherwise)
  double posting_m() const;            // mean pixel size in metres (geographic CRS: at the DEM's centre)
  long width() const;
  long height_px() const;
  std::size_t blocks_read() const;     // tile/strip reads from the file so far (a block read again counts again)
  std::size_t blocks_cached() const;   // blocks held now

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A float32 GeoTIFF DEM for tests and benchmarks: `epsg` names its CRS (projected or geographic; GeoKeys
// written with PixelIsArea, ModelTiepoint + ModelPixelScale), heights already above `datum` (written to the
// GeoTIFF's vertical keys for egm96 and egm2008; ellipsoid: none), NaN cells written as `nodata` (GDAL_NODATA).
// (x0, y0): model coordinates of the top-left pixel's CENTRE; dx, dy > 0 (rows run towards -y). tile > 0:
// tiled (multiple of 16), else strips of 16 rows.
struct DemRaster {
  int epsg = 4326;
  double x0 = 0, y0 = 0, dx = 1, dy = 1;
  long width = 0, height = 0;
  std::vector<float> data;  // row-major, width * height
  float nodata = -9999;
  std::string datum = "ellipsoid";
  int tile = 256;
};
void write_reference_dem(const std::string& path, const DemRaster& dem);

}  // namespace tpkit
