#include "tpkit/ortho/ortho_geotiff.hpp"

#include <geotiff/geotiff.h>
#include <geotiff/geovalues.h>
#include <geotiff/xtiffio.h>
#include <tiffio.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tiff_image.hpp"
#include "tpkit/core/version.hpp"

namespace tpkit {

namespace {
constexpr uint32_t kGdalNodata = 42113;

template <class T>
void difference_rows(unsigned char* data, long tile, int bands) {
  // TIFF horizontal predictor (2): each sample less the same band's sample of the pixel before, per row
  T* p = reinterpret_cast<T*>(data);
  for (long r = 0; r < tile; ++r) {
    T* row = p + r * tile * bands;
    for (long i = tile * bands - 1; i >= bands; --i) row[i] = static_cast<T>(row[i] - row[i - bands]);
  }
}
}  // namespace

SampleType sample_type_of(const std::string& format, const std::string& path) {
  if (format == "uint8") return SampleType::u8;
  if (format == "uint16") return SampleType::u16;
  if (format == "int16") return SampleType::i16;
  if (format == "uint32") return SampleType::u32;
  if (format == "int32") return SampleType::i32;
  if (format == "float") return SampleType::f32;
  if (format == "double") return SampleType::f64;
  throw InputError(path, 0, "samples of type " + format + ": tp-ortho writes uint8, uint16, int16, uint32, int32, float and double");
}

int sample_bytes(SampleType t) {
  switch (t) {
    case SampleType::u8: return 1;
    case SampleType::u16:
    case SampleType::i16: return 2;
    case SampleType::u32:
    case SampleType::i32:
    case SampleType::f32: return 4;
    case SampleType::f64: return 8;
  }
  return 1;
}

double to_sample(SampleType t, double v) {
  auto clamp = [&](double lo, double hi) { return std::min(hi, std::max(lo, std::round(v))); };
  switch (t) {
    case SampleType::u8: return clamp(0, 255);
    case SampleType::u16: return clamp(0, 65535);
    case SampleType::i16: return clamp(-32768, 32767);
    case SampleType::u32: return clamp(0, 4294967295.0);
    case SampleType::i32: return clamp(-2147483648.0, 2147483647.0);
    case SampleType::f32:
    case SampleType::f64: return v;
  }
  return v;
}

struct OrthoTiffWriter::Impl {
  std::string path, tmp;
  OrthoTiffLayout layout;
  TIFF* tif = nullptr;
  std::mutex mutex;
  std::vector<char> written;  // per tile
  bool failed = false, closed = false;
};

OrthoTiffWriter::OrthoTiffWriter(const std::string& path, const OrthoTiffLayout& layout) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.path = path;
  d.layout = layout;
  const OrthoGrid& g = layout.grid;
  claim_output(path);
  d.tmp = claim_temp(path);
  register_tiff_tags();
  const double bytes = static_cast<double>(g.width) * g.height * layout.bands * sample_bytes(layout.type);
  d.tif = XTIFFOpen(d.tmp.c_str(), bytes > 3.0 * (1u << 30) ? "w8" : "w");
  if (!d.tif) {
    discard_temp(d.tmp);
    throw InputError(path, 0, "cannot be written");
  }
  TIFF* tif = d.tif;
  const SampleType t = layout.type;
  const bool is_float = t == SampleType::f32 || t == SampleType::f64;
  const bool is_signed = t == SampleType::i16 || t == SampleType::i32;
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(g.width));
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(g.height));
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, static_cast<uint16_t>(layout.bands));
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, static_cast<uint16_t>(8 * sample_bytes(t)));
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, is_float ? SAMPLEFORMAT_IEEEFP : is_signed ? SAMPLEFORMAT_INT : SAMPLEFORMAT_UINT);
  const bool rgb = layout.rgb && layout.bands >= 3;
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, rgb ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
  const int extra = layout.bands - (rgb ? 3 : 1);
  if (extra > 0) {
    std::vector<uint16_t> kinds(static_cast<size_t>(extra), EXTRASAMPLE_UNSPECIFIED);
    TIFFSetField(tif, TIFFTAG_EXTRASAMPLES, static_cast<uint16_t>(extra), kinds.data());
  }
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
  TIFFSetField(tif, TIFFTAG_PREDICTOR, is_float ? PREDICTOR_NONE : PREDICTOR_HORIZONTAL);
  TIFFSetField(tif, TIFFTAG_TILEWIDTH, static_cast<uint32_t>(OrthoTiffLayout::kTile));
  TIFFSetField(tif, TIFFTAG_TILELENGTH, static_cast<uint32_t>(OrthoTiffLayout::kTile));
  TIFFSetField(tif, TIFFTAG_SOFTWARE, written_by().c_str());
  if (!layout.description.empty()) TIFFSetField(tif, TIFFTAG_IMAGEDESCRIPTION, layout.description.c_str());
  const std::string nd = std::isnan(layout.nodata) ? std::string("nan") : format_number(layout.nodata);
  TIFFSetField(tif, kGdalNodata, nd.c_str());
  // PixelIsArea: the tie point is the grid's top-left corner
  double scale[3] = {g.gsd, g.gsd, 0};
  double tie[6] = {0, 0, 0, g.x0, g.y0, 0};
  TIFFSetField(tif, TIFFTAG_GEOPIXELSCALE, 3, scale);
  TIFFSetField(tif, TIFFTAG_GEOTIEPOINTS, 6, tie);
  GTIF* gtif = GTIFNew(tif);
  if (!gtif) {
    XTIFFClose(tif);
    d.tif = nullptr;
    discard_temp(d.tmp);
    throw InputError(path, 0, "cannot write GeoTIFF keys");
  }
  GTIFKeySet(gtif, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeProjected);
  GTIFKeySet(gtif, GTRasterTypeGeoKey, TYPE_SHORT, 1, RasterPixelIsArea);
  GTIFKeySet(gtif, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, g.epsg);
  GTIFWriteKeys(gtif);
  GTIFFree(gtif);
  d.written.assign(static_cast<size_t>(layout.tiles_across() * layout.tiles_down()), 0);
}

OrthoTiffWriter::~OrthoTiffWriter() {
  if (impl_->closed) return;
  if (impl_->tif) XTIFFClose(impl_->tif);
  discard_temp(impl_->tmp);
}

void OrthoTiffWriter::write_tile(long tx, long ty, std::vector<unsigned char>& samples) {
  Impl& d = *impl_;
  const long T = OrthoTiffLayout::kTile;
  const int bands = d.layout.bands;
  if (samples.size() != static_cast<size_t>(T * T * bands * sample_bytes(d.layout.type)))
    throw std::logic_error("OrthoTiffWriter: a tile of the wrong size");
  switch (d.layout.type) {
    case SampleType::u8: difference_rows<uint8_t>(samples.data(), T, bands); break;
    case SampleType::u16:
    case SampleType::i16: difference_rows<uint16_t>(samples.data(), T, bands); break;
    case SampleType::u32:
    case SampleType::i32: difference_rows<uint32_t>(samples.data(), T, bands); break;
    default: break;
  }
  // compressed here, by the calling thread; only the write is serialized
  uLongf size = compressBound(static_cast<uLong>(samples.size()));
  thread_local std::vector<unsigned char> packed;  // kept from tile to tile (fresh pages cost faults)
  packed.resize(size);
  if (compress2(packed.data(), &size, samples.data(), static_cast<uLong>(samples.size()), Z_BEST_SPEED) != Z_OK)
    throw std::runtime_error(d.path + ": deflate failed");
  std::lock_guard<std::mutex> lock(d.mutex);
  const uint32_t index = TIFFComputeTile(d.tif, static_cast<uint32_t>(tx * T), static_cast<uint32_t>(ty * T), 0, 0);
  if (TIFFWriteRawTile(d.tif, index, packed.data(), static_cast<tmsize_t>(size)) < 0) {
    d.failed = true;
    throw InputError(d.path, 0, "write error (disk full?)");
  }
  d.written[static_cast<size_t>(ty * d.layout.tiles_across() + tx)] = 1;
}

void OrthoTiffWriter::close() {
  Impl& d = *impl_;
  for (char w : d.written)
    if (!w) throw std::logic_error("OrthoTiffWriter: a tile was not written");
  const bool ok = TIFFWriteDirectory(d.tif) != 0 && !d.failed;
  XTIFFClose(d.tif);
  d.tif = nullptr;
  if (!ok) throw InputError(d.path, 0, "write error (disk full?)");
  d.closed = true;
  finish_output(d.tmp, d.path);
}

OrthoFileInfo read_ortho_info(const std::string& path) {
  check_input_file(path, InputKind::image);
  register_tiff_tags();
  TIFF* tif = XTIFFOpen(path.c_str(), "r");
  if (!tif) throw InputError(path, 0, "cannot be read as a TIFF");
  struct Close {
    TIFF* t;
    ~Close() { XTIFFClose(t); }
  } closer{tif};
  OrthoFileInfo info;
  uint32_t w = 0, h = 0;
  uint16_t spp = 1;
  TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &w);
  TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &h);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &spp);
  info.bands = spp;
  char* nd = nullptr;
  if (TIFFGetField(tif, kGdalNodata, &nd) && nd) {
    char* end = nullptr;
    info.nodata = std::strtod(nd, &end);
    info.has_nodata = end != nd;
  }
  GTIF* gtif = GTIFNew(tif);
  if (!gtif) throw InputError(path, 0, "no GeoTIFF keys (not an ortho)");
  unsigned short pcs = 0, raster = RasterPixelIsArea;
  const bool has_pcs = GTIFKeyGet(gtif, ProjectedCSTypeGeoKey, &pcs, 0, 1) == 1;
  GTIFKeyGet(gtif, GTRasterTypeGeoKey, &raster, 0, 1);
  GTIFFree(gtif);
  if (!has_pcs || pcs == 0 || pcs == KvUserDefined)
    throw InputError(path, 0, "no projected CRS named by an EPSG code in its GeoTIFF keys (ProjectedCSTypeGeoKey)");
  uint16_t n = 0;
  double* scale = nullptr;
  double* tie = nullptr;
  double* matrix = nullptr;
  if (TIFFGetField(tif, TIFFTAG_GEOTRANSMATRIX, &n, &matrix)) throw InputError(path, 0, "a ModelTransformation grid (rotated?): not an ortho grid");
  if (!TIFFGetField(tif, TIFFTAG_GEOPIXELSCALE, &n, &scale) || n < 2) throw InputError(path, 0, "no ModelPixelScale tag");
  uint16_t nt = 0;
  if (!TIFFGetField(tif, TIFFTAG_GEOTIEPOINTS, &nt, &tie) || nt < 6) throw InputError(path, 0, "no ModelTiepoint tag");
  if (!(scale[0] > 0) || std::abs(scale[0] - scale[1]) > 1e-9 * scale[0])
    throw InputError(path, 0, "pixels of " + format_number(scale[0]) + " x " + format_number(scale[1]) + ": not square");
  OrthoGrid& g = info.grid;
  g.epsg = pcs;
  g.gsd = scale[0];
  g.width = w;
  g.height = h;
  // the corner of raster point (I, J) = (tie[0], tie[1]); PixelIsPoint: that point is a pixel's centre
  const double shift = raster == RasterPixelIsPoint ? 0.5 : 0.0;
  g.x0 = tie[3] - (tie[0] + shift) * g.gsd;
  g.y0 = tie[4] + (tie[1] + shift) * g.gsd;
  return info;
}

}  // namespace tpkit
