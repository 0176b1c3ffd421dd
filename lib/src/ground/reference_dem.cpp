#include "tpkit/ground/reference_dem.hpp"

#include <geotiff/geo_normalize.h>
#include <geotiff/geotiff.h>
#include <geotiff/geovalues.h>
#include <geotiff/xtiffio.h>
#include <proj.h>
#include <tiffio.h>

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <list>
#include <mutex>
#include <unordered_map>

#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "geotiff_tags.hpp"

namespace tpkit {

namespace {

constexpr double kDegToRad = M_PI / 180;

// One PROJ context per object: PJ objects are not shared between threads (calls are serialized by a mutex).
struct ProjHandle {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* pj = nullptr;
  ProjHandle() { proj_log_level(ctx, PJ_LOG_NONE); }
  ~ProjHandle() {
    if (pj) proj_destroy(pj);
    proj_context_destroy(ctx);
  }
  ProjHandle(const ProjHandle&) = delete;
  ProjHandle& operator=(const ProjHandle&) = delete;
};

// GDAL's nodata tag (42113, ASCII) known to libtiff for every file opened after the first DEM: a tag extender,
// chained to the one before it (libgeotiff's), installed once.
TIFFExtendProc previous_extender = nullptr;
void gdal_tags_extender(TIFF* tif) {
  static const TIFFFieldInfo info[] = {
      {TIFFTAG_GDAL_NODATA, -1, -1, TIFF_ASCII, FIELD_CUSTOM, 1, 0, const_cast<char*>("GDALNoDataValue")}};
  if (!TIFFFindField(tif, TIFFTAG_GDAL_NODATA, TIFF_ANY)) TIFFMergeFieldInfo(tif, info, 1);
  if (previous_extender) previous_extender(tif);
}
TIFF* open_tiff(const std::string& path, const char* mode) {
  static std::once_flag once;
  std::call_once(once, [] { previous_extender = TIFFSetTagExtender(gdal_tags_extender); });
  return XTIFFOpen(path.c_str(), mode);
}

// PROJ grid names tried for each named geoid (the newer PROJ-data name first).
std::vector<std::string> geoid_grids(const std::string& datum) {
  if (datum == "egm96") return {"egm96_15.gtx", "us_nga_egm96_15.tif"};
  if (datum == "egm2008") return {"us_nga_egm08_25.tif", "egm08_25.gtx"};
  return {datum};
}

// A grid named in a datum option goes into a PROJ definition: letters, digits and . _ - / only, as PROJ reads
// '@' as "optional: use no grid when missing", ',' as a list, and a space or '+' as further parameters.
bool plain_grid_name(const std::string& grid) {
  return std::all_of(grid.begin(), grid.end(),
                     [](unsigned char c) { return std::isalnum(c) || c == '.' || c == '_' || c == '-' || c == '/'; });
}

// GDAL_NODATA in the band's sample type, as GDAL compares it: for float32 the text's nearest float ("-3.4e+38"
// is the float -3.39999995e38, not the double -3.4e38), a value just beyond FLT_MAX (its text rounded) FLT_MAX.
double nodata_in_type(double v, uint16_t bits, uint16_t format) {
  if (format != SAMPLEFORMAT_IEEEFP || bits != 32 || !std::isfinite(v)) return v;
  if (std::fabs(v) > FLT_MAX) return std::fabs(v) <= FLT_MAX * (1 + 1e-7) ? std::copysign(FLT_MAX, v) : v;
  return static_cast<float>(v);
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// VerticalDatum: N(lon, lat) from PROJ's vgridshift with multiplier 1 applied to a zero height.
struct VerticalDatum::Impl {
  ProjHandle proj;
  mutable std::mutex mutex;
};

VerticalDatum::VerticalDatum(const std::string& datum, const std::string& what) : name_(datum) {
  if (datum.empty()) throw InputError(what + ": empty vertical datum (ellipsoid|egm96|egm2008|GRID)");
  if (datum == "ellipsoid") return;
  if (!plain_grid_name(datum))
    throw InputError(what + " '" + datum + "': neither ellipsoid, egm96, egm2008 nor a grid's file name (letters, digits, "
                     ". _ - / only: PROJ would read '@' as an optional grid, ',' as a list, a space or '+' as more parameters)");
  impl_ = std::make_unique<Impl>();
  std::string tried;
  for (const std::string& grid : geoid_grids(datum)) {
    const std::string def = "+proj=vgridshift +grids=" + grid + " +multiplier=1";
    impl_->proj.pj = proj_create(impl_->proj.ctx, def.c_str());
    if (impl_->proj.pj) return;
    tried += (tried.empty() ? "" : " nor ") + grid;
  }
  const bool named = datum == "egm96" || datum == "egm2008";
  throw InputError(what + " " + datum + ": geoid grid " + tried + " not found" +
                   (named ? " (install Debian's proj-data, or put the grid in PROJ's search path, PROJ_DATA)"
                          : " (neither a file PROJ reads as a vertical grid nor a grid in PROJ's search path)"));
}

VerticalDatum::~VerticalDatum() = default;

bool VerticalDatum::is_ellipsoid() const { return !impl_; }

double VerticalDatum::undulation(double lon, double lat) const {
  if (!impl_) return 0;
  std::lock_guard<std::mutex> lock(impl_->mutex);
  PJ_COORD c = proj_coord(lon * kDegToRad, lat * kDegToRad, 0, 0);
  proj_errno_reset(impl_->proj.pj);
  PJ_COORD r = proj_trans(impl_->proj.pj, PJ_FWD, c);
  if (proj_errno(impl_->proj.pj) != 0 || !std::isfinite(r.xyz.z) || r.xyz.z == HUGE_VAL) return NAN;
  return r.xyz.z;
}

// ---------------------------------------------------------------------------------------------------------
// ReferenceDem: the file's layout and georeferencing (open), a block cache (blocks), sampling (height).
struct ReferenceDem::Impl {
  std::string path;
  TIFF* tif = nullptr;
  long width = 0, height = 0;
  // Blocks: tiles, strips taken as tiles as wide as the image, or (by_rows: strips above kMaxDemBlockBytes)
  // bands of rows read row by row. libtiff decodes a compressed strip's rows only in order, from its first:
  // next_row is the row it decodes next (-1: unknown), strip_rows the rows per strip.
  bool tiled = false, by_rows = false;
  long block_w = 0, block_h = 0, blocks_across = 0, strip_rows = 0, next_row = -1;
  uint16_t bits = 32, format = SAMPLEFORMAT_IEEEFP;
  bool has_nodata = false;
  double nodata = 0;
  // Model (x, y) of pixel centre (c, r): x = a[0] + a[1] c + a[2] r, y = a[3] + a[4] c + a[5] r; inverse inv.
  double a[6] = {0, 1, 0, 0, 0, -1}, inv[6] = {0, 1, 0, 0, 0, -1};
  bool geographic = false;
  double xy_unit = 1;  // metres per model unit of a projected CRS
  std::string crs;
  double posting = 0;
  ProjHandle to_dem;  // WGS 84 lon, lat -> DEM x, y
  std::unique_ptr<VerticalDatum> datum;
  double z_unit = 1;  // metres per stored height unit
  // Cache: LRU list of block indices, map index -> (data, list position).
  std::size_t max_blocks = 1;
  std::list<long> lru;
  std::unordered_map<long, std::pair<std::vector<float>, std::list<long>::iterator>> blocks;
  std::size_t reads = 0;
  mutable std::mutex mutex;

  ~Impl() {
    if (tif) XTIFFClose(tif);
  }
  [[noreturn]] void fail(const std::string& reason) const { throw InputError(path, 0, reason); }

  void read_layout();
  void read_georeferencing(GTIF* gtif);
  void read_crs(GTIF* gtif);
  std::string read_vertical(GTIF* gtif, const std::string& option);
  const std::vector<float>& block(long index);
  bool cell(long c, long r, double& z);
  bool to_pixel(double lon, double lat, double& fc, double& fr);
  bool bilinear(double fc, double fr, double& z, double* dz_dc, double* dz_dr);
};

void ReferenceDem::Impl::read_layout() {
  uint32_t w = 0, h = 0;
  uint16_t spp = 1;
  TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &w);
  TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &h);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLEFORMAT, &format);
  width = w;
  height = h;
  if (width < 2 || height < 2) fail("a DEM needs at least 2x2 cells (" + std::to_string(width) + "x" + std::to_string(height) + ")");
  if (spp != 1) fail("a DEM has one band (" + std::to_string(spp) + " here)");
  const bool ok = (format == SAMPLEFORMAT_IEEEFP && (bits == 32 || bits == 64)) ||
                  ((format == SAMPLEFORMAT_INT || format == SAMPLEFORMAT_UINT) && (bits == 8 || bits == 16 || bits == 32));
  if (!ok) fail("DEM samples of " + std::to_string(bits) + " bits, format " + std::to_string(format) + ": not supported");
  tiled = TIFFIsTiled(tif);
  if (tiled) {
    uint32_t tw = 0, th = 0;
    TIFFGetField(tif, TIFFTAG_TILEWIDTH, &tw);
    TIFFGetField(tif, TIFFTAG_TILELENGTH, &th);
    block_w = tw;
    block_h = th;
  } else {
    uint32_t rps = 0;
    TIFFGetFieldDefaulted(tif, TIFFTAG_ROWSPERSTRIP, &rps);
    block_w = width;
    block_h = std::min<long>(rps, height);
  }
  if (block_w <= 0 || block_h <= 0) fail("no tile or strip size");
  const auto mib = [](uint64_t bytes) { return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB"; };
  const uint64_t block_bytes = tiled ? TIFFTileSize64(tif) : TIFFStripSize64(tif);
  if (block_bytes > kMaxDemBlockBytes) {
    const std::string bound = mib(kMaxDemBlockBytes) + " a DEM block may take";
    if (tiled)
      fail("tiles of " + std::to_string(block_w) + "x" + std::to_string(block_h) + " cells (" + mib(block_bytes) +
           " decoded) exceed the " + bound + " (libtiff decodes a tile only whole): rewrite it with smaller tiles "
           "(gdal_translate -co TILED=YES)");
    const uint64_t row = TIFFScanlineSize64(tif);
    if (row > kMaxDemBlockBytes) fail("rows of " + mib(row) + " exceed the " + bound);
    // Bands of about 1 MiB: a miss costs a restart of the strip's decoding when it lies before the last row read.
    by_rows = true;
    strip_rows = block_h;
    block_h = std::max<long>(1, std::min<long>(block_h, static_cast<long>((std::size_t(1) << 20) / row)));
  }
  blocks_across = (width + block_w - 1) / block_w;
  char* nd = nullptr;
  if (TIFFGetField(tif, TIFFTAG_GDAL_NODATA, &nd) && nd) {
    char* end = nullptr;
    nodata = nodata_in_type(std::strtod(nd, &end), bits, format);
    has_nodata = end != nd;
  }
}

void ReferenceDem::Impl::read_georeferencing(GTIF* gtif) {
  const std::array<double, 6> m = geotiff_pixel_to_model(tif, gtif, path);
  std::copy(m.begin(), m.end(), a);
  const double det = a[1] * a[5] - a[2] * a[4];
  inv[1] = a[5] / det; inv[2] = -a[2] / det; inv[4] = -a[4] / det; inv[5] = a[1] / det;
  inv[0] = -(inv[1] * a[0] + inv[2] * a[3]);
  inv[3] = -(inv[4] * a[0] + inv[5] * a[3]);
}

// The vertical datum: `option` when given (refused where the keys name another), else the keys'. A vertical
// CRS or datum code the keys give but tpkit does not name needs `option` (its grid). Sets z_unit.
std::string ReferenceDem::Impl::read_vertical(GTIF* gtif, const std::string& option) {
  unsigned short cs = 0, vd = 0, units = 0;
  std::string keys, said;  // the keys' datum ("?" for a code tpkit does not name), and how the keys say it
  if (GTIFKeyGetSHORT(gtif, VerticalCSTypeGeoKey, &cs, 0, 1) && cs != KvUserDefined) {
    said = "vertical CRS EPSG:" + std::to_string(cs);
    keys = cs == 5773 ? "egm96" : cs == 3855 ? "egm2008" : cs == 5030 ? "ellipsoid" : "?";
  } else if (GTIFKeyGetSHORT(gtif, VerticalDatumGeoKey, &vd, 0, 1) && vd != KvUserDefined) {
    said = "vertical datum EPSG:" + std::to_string(vd);
    keys = vd == 5171 ? "egm96" : vd == 1027 ? "egm2008" : vd == 6326 ? "ellipsoid" : "?";
  }
  if (GTIFKeyGetSHORT(gtif, VerticalUnitsGeoKey, &units, 0, 1) && units != Linear_Meter) {
    double metres = 0;
    if (!GTIFGetUOMLengthInfoEx(to_dem.ctx, units, nullptr, &metres) || !(metres > 0))
      fail("vertical unit " + std::to_string(units) + " in the GeoTIFF keys (VerticalUnitsGeoKey): not a length unit EPSG knows");
    z_unit = metres;
  }
  if (option.empty()) {
    if (keys == "?")
      fail("the GeoTIFF keys give " + said + " for its heights, not one tpkit knows (EGM96 height 5773, EGM2008 height "
           "3855, WGS 84 ellipsoidal 5030): give its geoid grid with --dem-datum");
    return keys.empty() ? "ellipsoid" : keys;
  }
  if (!keys.empty() && keys != "?" && option != keys)
    fail("--dem-datum " + option + " disagrees with the GeoTIFF keys' " + said + " (" + keys +
         "): leave --dem-datum out to use the keys");
  return option;
}

void ReferenceDem::Impl::read_crs(GTIF* gtif) {
  unsigned short model = 0, code = 0;
  GTIFKeyGetSHORT(gtif, GTModelTypeGeoKey, &model, 0, 1);
  std::string def;
  if (model == ModelTypeProjected && GTIFKeyGetSHORT(gtif, ProjectedCSTypeGeoKey, &code, 0, 1) && code != KvUserDefined) {
    def = "EPSG:" + std::to_string(code);
  } else if (model == ModelTypeGeographic && GTIFKeyGetSHORT(gtif, GeographicTypeGeoKey, &code, 0, 1) &&
             code != KvUserDefined) {
    def = "EPSG:" + std::to_string(code);
  } else if (model == ModelTypeProjected || model == ModelTypeGeographic) {
    GTIFDefn defn;
    if (GTIFGetDefn(gtif, &defn)) {
      if (char* p4 = GTIFGetProj4Defn(&defn)) {
        def = p4;
        GTIFFreeMemory(p4);
      }
    }
    if (def.empty()) fail("a user-defined CRS that libgeotiff cannot describe");
  } else {
    fail("no CRS in the GeoTIFF keys (GTModelTypeGeoKey " + std::to_string(model) + ": neither projected nor geographic)");
  }
  crs = def;
  geographic = model == ModelTypeGeographic;
  PJ* raw = proj_create_crs_to_crs(to_dem.ctx, "EPSG:4326", def.c_str(), nullptr);
  if (!raw) fail("unknown CRS " + def + " (PROJ: " + proj_context_errno_string(to_dem.ctx, proj_context_errno(to_dem.ctx)) + ")");
  to_dem.pj = proj_normalize_for_visualization(to_dem.ctx, raw);  // lon, lat in; easting (lon), northing (lat) out
  proj_destroy(raw);
  if (!to_dem.pj) fail("CRS " + def + ": PROJ cannot normalize its axis order");
  // A projected CRS's unit from its first axis (a US-feet state plane's pixel scale is in feet; PROJ's
  // transformation already gives feet, only the posting in metres needs it). A PROJ string is made a CRS.
  if (!geographic) {
    PJ* c = proj_create(to_dem.ctx, (def[0] == '+' ? def + " +type=crs" : def).c_str());
    if (c && proj_get_type(c) == PJ_TYPE_BOUND_CRS) {
      PJ* source = proj_get_source_crs(to_dem.ctx, c);
      proj_destroy(c);
      c = source;
    }
    PJ* cs = c ? proj_crs_get_coordinate_system(to_dem.ctx, c) : nullptr;
    double metres = 0;
    if (cs && proj_cs_get_axis_info(to_dem.ctx, cs, 0, nullptr, nullptr, nullptr, &metres, nullptr, nullptr, nullptr) && metres > 0)
      xy_unit = metres;
    if (cs) proj_destroy(cs);
    if (c) proj_destroy(c);
  }
}

const std::vector<float>& ReferenceDem::Impl::block(long index) {
  auto it = blocks.find(index);
  if (it != blocks.end()) {
    lru.splice(lru.begin(), lru, it->second.second);
    return it->second.first;
  }
  tmsize_t got = 0;
  std::vector<unsigned char> raw;
  if (by_rows) {
    // Rows r0 .. r1 - 1, decoded from where libtiff is in their strip when it is before r0, else from the strip's
    // first row; rows before r0 go to a scratch row.
    const tmsize_t row = TIFFScanlineSize(tif);
    const long r0 = index * block_h, r1 = std::min(r0 + block_h, height), strip_start = r0 / strip_rows * strip_rows;
    raw.resize(static_cast<std::size_t>(row * (r1 - r0)));
    const long from = next_row >= strip_start && next_row <= r0 ? next_row : strip_start;
    std::vector<unsigned char> skipped(from < r0 ? static_cast<std::size_t>(row) : 0);
    next_row = -1;
    for (long r = from; r < r1; ++r)
      if (TIFFReadScanline(tif, r < r0 ? skipped.data() : raw.data() + (r - r0) * row, static_cast<uint32_t>(r), 0) < 0)
        fail("row " + std::to_string(r) + " cannot be read");
    next_row = r1;
    got = row * (r1 - r0);
  } else {
    const tmsize_t bytes = tiled ? TIFFTileSize(tif) : TIFFStripSize(tif);
    raw.resize(static_cast<std::size_t>(bytes));
    got = tiled ? TIFFReadEncodedTile(tif, static_cast<uint32_t>(index), raw.data(), bytes)
                : TIFFReadEncodedStrip(tif, static_cast<uint32_t>(index), raw.data(), bytes);
    if (got < 0) fail((tiled ? "tile " : "strip ") + std::to_string(index) + " cannot be read");
  }
  ++reads;
  const std::size_t n = static_cast<std::size_t>(block_w * block_h);
  std::vector<float> out(n, NAN);
  const std::size_t avail = static_cast<std::size_t>(got) / (bits / 8);
  for (std::size_t i = 0; i < std::min(n, avail); ++i) {
    const unsigned char* p = raw.data() + i * (bits / 8);
    double v = 0;
    if (format == SAMPLEFORMAT_IEEEFP) {
      if (bits == 32) { float f; std::memcpy(&f, p, 4); v = f; } else { std::memcpy(&v, p, 8); }
    } else if (format == SAMPLEFORMAT_INT) {
      if (bits == 8) v = *reinterpret_cast<const int8_t*>(p);
      else if (bits == 16) { int16_t s; std::memcpy(&s, p, 2); v = s; }
      else { int32_t s; std::memcpy(&s, p, 4); v = s; }
    } else {
      if (bits == 8) v = *p;
      else if (bits == 16) { uint16_t s; std::memcpy(&s, p, 2); v = s; }
      else { uint32_t s; std::memcpy(&s, p, 4); v = s; }
    }
    out[i] = (has_nodata && v == nodata) ? NAN : static_cast<float>(v);
  }
  if (blocks.size() >= max_blocks) {
    blocks.erase(lru.back());
    lru.pop_back();
  }
  lru.push_front(index);
  auto& slot = blocks[index];
  slot.first = std::move(out);
  slot.second = lru.begin();
  return slot.first;
}

bool ReferenceDem::Impl::cell(long c, long r, double& z) {
  if (c < 0 || r < 0 || c >= width || r >= height) return false;
  const long bx = c / block_w, by = r / block_h;
  const std::vector<float>& b = block(by * blocks_across + bx);
  z = b[static_cast<std::size_t>((r - by * block_h) * block_w + (c - bx * block_w))];
  return std::isfinite(z);
}

bool ReferenceDem::Impl::to_pixel(double lon, double lat, double& fc, double& fr) {
  proj_errno_reset(to_dem.pj);
  const PJ_COORD p = proj_trans(to_dem.pj, PJ_FWD, proj_coord(lon, lat, 0, 0));
  if (proj_errno(to_dem.pj) != 0 || !std::isfinite(p.xy.x) || !std::isfinite(p.xy.y) || p.xy.x == HUGE_VAL) return false;
  fc = inv[0] + inv[1] * p.xy.x + inv[2] * p.xy.y;
  fr = inv[3] + inv[4] * p.xy.x + inv[5] * p.xy.y;
  return true;
}

bool ReferenceDem::Impl::bilinear(double fc, double fr, double& z, double* dz_dc, double* dz_dr) {
  if (!(fc >= 0) || !(fr >= 0) || fc > width - 1 || fr > height - 1) return false;
  const long c0 = std::min(static_cast<long>(fc), width - 2), r0 = std::min(static_cast<long>(fr), height - 2);
  double z00, z10, z01, z11;
  if (!cell(c0, r0, z00) || !cell(c0 + 1, r0, z10) || !cell(c0, r0 + 1, z01) || !cell(c0 + 1, r0 + 1, z11)) return false;
  const double u = fc - c0, v = fr - r0;
  z = (1 - v) * ((1 - u) * z00 + u * z10) + v * ((1 - u) * z01 + u * z11);
  if (dz_dc) *dz_dc = (1 - v) * (z10 - z00) + v * (z11 - z01);
  if (dz_dr) *dz_dr = (1 - u) * (z01 - z00) + u * (z11 - z10);
  return true;
}

ReferenceDem::ReferenceDem(const std::string& path, const ReferenceDemOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.path = path;
  check_input_file(path, InputKind::image);  // libtiff's open blocks on a FIFO for ever
  TIFFSetErrorHandler(nullptr);
  TIFFSetWarningHandler(nullptr);
  d.tif = open_tiff(path, "r");
  if (!d.tif) throw InputError(path, 0, "cannot be read as a TIFF");
  d.read_layout();
  GTIF* gtif = GTIFNew(d.tif);
  if (!gtif) d.fail("no GeoTIFF keys (no georeferencing)");
  try {
    d.read_georeferencing(gtif);
    d.read_crs(gtif);
    const std::string datum = d.read_vertical(gtif, options.datum);
    d.datum = std::make_unique<VerticalDatum>(
        datum, options.datum.empty() ? path + ": the GeoTIFF keys' vertical datum" : "--dem-datum (for " + path + ")");
  } catch (...) {
    GTIFFree(gtif);
    throw;
  }
  GTIFFree(gtif);
  const std::size_t block_bytes = static_cast<std::size_t>(d.block_w * d.block_h) * sizeof(float);
  d.max_blocks = std::max<std::size_t>(4, options.cache_bytes / std::max<std::size_t>(1, block_bytes));
  // Posting in metres: pixel steps along columns and rows, in degrees converted at the centre when geographic,
  // in the CRS's unit converted when projected.
  double sx = std::hypot(d.a[1], d.a[4]), sy = std::hypot(d.a[2], d.a[5]);
  if (d.geographic) {
    const double lat = d.a[3] + d.a[4] * (d.width - 1) / 2.0 + d.a[5] * (d.height - 1) / 2.0;
    sx *= 111320 * std::cos(lat * kDegToRad);
    sy *= 110574;
  } else {
    sx *= d.xy_unit;
    sy *= d.xy_unit;
  }
  d.posting = (sx + sy) / 2;
}

ReferenceDem::~ReferenceDem() = default;

bool ReferenceDem::height(double lon, double lat, double& h, double* grad) const {
  Impl& d = *impl_;
  double z = 0, dzc = 0, dzr = 0, fc = 0, fr = 0;
  {
    std::lock_guard<std::mutex> lock(d.mutex);
    if (!d.to_pixel(lon, lat, fc, fr) || !d.bilinear(fc, fr, z, grad ? &dzc : nullptr, grad ? &dzr : nullptr)) return false;
    if (grad) {
      // Chain rule through the projection: pixel coordinates per degree by finite differences (1e-5 deg).
      const double e = 1e-5;
      double fc1, fr1, fc2, fr2;
      if (!d.to_pixel(lon + e, lat, fc1, fr1) || !d.to_pixel(lon, lat + e, fc2, fr2)) return false;
      grad[0] = d.z_unit * (dzc * (fc1 - fc) + dzr * (fr1 - fr)) / e;
      grad[1] = d.z_unit * (dzc * (fc2 - fc) + dzr * (fr2 - fr)) / e;
    }
  }
  const double n = d.datum->undulation(lon, lat);
  if (!std::isfinite(n)) return false;
  h = z * d.z_unit + n;
  return std::isfinite(h);
}

void ReferenceDem::heights(std::size_t n, const double* lon, const double* lat, double* h) const {
  Impl& d = *impl_;
  std::vector<double> x(lon, lon + n), y(lat, lat + n);
  {
    std::lock_guard<std::mutex> lock(d.mutex);
    proj_errno_reset(d.to_dem.pj);
    proj_trans_generic(d.to_dem.pj, PJ_FWD, x.data(), sizeof(double), n, y.data(), sizeof(double), n, nullptr, 0, 0, nullptr, 0, 0);
    for (std::size_t i = 0; i < n; ++i) {
      double z = 0;
      const bool known = std::isfinite(x[i]) && std::isfinite(y[i]) && x[i] != HUGE_VAL &&
                         d.bilinear(d.inv[0] + d.inv[1] * x[i] + d.inv[2] * y[i], d.inv[3] + d.inv[4] * x[i] + d.inv[5] * y[i], z, nullptr, nullptr);
      h[i] = known ? z * d.z_unit : NAN;
    }
  }
  if (d.datum->is_ellipsoid()) return;
  for (std::size_t i = 0; i < n; ++i)
    if (std::isfinite(h[i])) h[i] += d.datum->undulation(lon[i], lat[i]);  // NaN where the grid has none
}

bool ReferenceDem::slope_aspect(double lon, double lat, double& slope_deg, double& aspect_deg) const {
  double h, g[2];
  if (!height(lon, lat, h, g)) return false;
  const double de = g[0] / (111320 * std::cos(lat * kDegToRad)), dn = g[1] / 110574;  // m per m east, north
  slope_deg = std::atan(std::hypot(de, dn)) / kDegToRad;
  aspect_deg = std::atan2(-de, -dn) / kDegToRad;  // downhill direction, clockwise from north
  if (aspect_deg < 0) aspect_deg += 360;
  return true;
}

const std::string& ReferenceDem::path() const { return impl_->path; }
std::string ReferenceDem::crs() const { return impl_->crs; }
const std::string& ReferenceDem::datum() const { return impl_->datum->name(); }
double ReferenceDem::vertical_unit_m() const { return impl_->z_unit; }
double ReferenceDem::posting_m() const { return impl_->posting; }
long ReferenceDem::width() const { return impl_->width; }
long ReferenceDem::height_px() const { return impl_->height; }
std::size_t ReferenceDem::blocks_read() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->reads;
}
std::size_t ReferenceDem::blocks_cached() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->blocks.size();
}

// ---------------------------------------------------------------------------------------------------------
void write_reference_dem(const std::string& path, const DemRaster& dem) {
  if (dem.width < 1 || dem.height < 1 || dem.data.size() != static_cast<std::size_t>(dem.width * dem.height))
    throw InputError(path, 0, "DEM raster size and data do not agree");
  TIFF* tif = open_tiff(path, "w");
  if (!tif) throw InputError(path, 0, "cannot be written");
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(dem.width));
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(dem.height));
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 32);
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_NONE);
  const std::string nd = std::to_string(dem.nodata);
  TIFFSetField(tif, TIFFTAG_GDAL_NODATA, nd.c_str());
  // PixelIsArea: the tie point is the top-left pixel's corner, half a pixel from its centre.
  double scale[3] = {dem.dx, dem.dy, 0};
  double tie[6] = {0, 0, 0, dem.x0 - dem.dx / 2, dem.y0 + dem.dy / 2, 0};
  TIFFSetField(tif, TIFFTAG_GEOPIXELSCALE, 3, scale);
  TIFFSetField(tif, TIFFTAG_GEOTIEPOINTS, 6, tie);
  GTIF* gtif = GTIFNew(tif);
  PJ_CONTEXT* ctx = proj_context_create();
  proj_log_level(ctx, PJ_LOG_NONE);
  const std::string epsg = "EPSG:" + std::to_string(dem.epsg);
  PJ* crs = proj_create(ctx, epsg.c_str());
  const bool geographic = crs && proj_get_type(crs) == PJ_TYPE_GEOGRAPHIC_2D_CRS;
  const bool known = crs != nullptr;
  if (crs) proj_destroy(crs);
  proj_context_destroy(ctx);
  if (!known) {
    GTIFFree(gtif);
    XTIFFClose(tif);
    std::remove(path.c_str());
    throw InputError(path, 0, "unknown CRS " + epsg);
  }
  GTIFKeySet(gtif, GTModelTypeGeoKey, TYPE_SHORT, 1, geographic ? ModelTypeGeographic : ModelTypeProjected);
  GTIFKeySet(gtif, GTRasterTypeGeoKey, TYPE_SHORT, 1, RasterPixelIsArea);
  GTIFKeySet(gtif, geographic ? GeographicTypeGeoKey : ProjectedCSTypeGeoKey, TYPE_SHORT, 1, dem.epsg);
  // Vertical keys: EPSG 5773 is EGM96 height, 3855 EGM2008 height (a ReferenceDem takes its datum from them).
  if (dem.datum == "egm96") GTIFKeySet(gtif, VerticalCSTypeGeoKey, TYPE_SHORT, 1, 5773);
  if (dem.datum == "egm2008") GTIFKeySet(gtif, VerticalCSTypeGeoKey, TYPE_SHORT, 1, 3855);
  GTIFWriteKeys(gtif);
  GTIFFree(gtif);
  bool ok = true;
  auto value = [&](long c, long r) {
    if (c >= dem.width || r >= dem.height) return dem.nodata;
    const float v = dem.data[static_cast<std::size_t>(r * dem.width + c)];
    return std::isfinite(v) ? v : dem.nodata;
  };
  if (dem.tile > 0) {
    const long t = dem.tile;
    TIFFSetField(tif, TIFFTAG_TILEWIDTH, static_cast<uint32_t>(t));
    TIFFSetField(tif, TIFFTAG_TILELENGTH, static_cast<uint32_t>(t));
    std::vector<float> buf(static_cast<std::size_t>(t * t));
    for (long ty = 0; ty < dem.height && ok; ty += t)
      for (long tx = 0; tx < dem.width && ok; tx += t) {
        for (long r = 0; r < t; ++r)
          for (long c = 0; c < t; ++c) buf[static_cast<std::size_t>(r * t + c)] = value(tx + c, ty + r);
        ok = TIFFWriteTile(tif, buf.data(), static_cast<uint32_t>(tx), static_cast<uint32_t>(ty), 0, 0) >= 0;
      }
  } else {
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 16);
    std::vector<float> row(static_cast<std::size_t>(dem.width));
    for (long r = 0; r < dem.height && ok; ++r) {
      for (long c = 0; c < dem.width; ++c) row[static_cast<std::size_t>(c)] = value(c, r);
      ok = TIFFWriteScanline(tif, row.data(), static_cast<uint32_t>(r), 0) >= 0;
    }
  }
  XTIFFClose(tif);
  if (!ok) {
    std::remove(path.c_str());
    throw InputError(path, 0, "write failed");
  }
}

}  // namespace tpkit
