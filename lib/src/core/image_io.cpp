#include "tpkit/core/image_io.hpp"

#include <tiffio.h>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/nitf_image.hpp"
#include "tpkit/core/oiio_images.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tiff_image.hpp"
#include "tpkit/core/version.hpp"

namespace tpkit {

// Each file goes to the reader of its format: NITF (nitf_image.hpp: OIIO has none), TIFF through libtiff
// (tiff_image.hpp), and the rest, or a TIFF layout libtiff's reader leaves aside, through OpenImageIO's
// module (oiio_images.hpp).
ImageInfo image_info(const std::string& path) {
  check_input_file(path, InputKind::image);  // "is a directory", "no such file", "not a regular file"
  note_input(path);
  if (is_nitf_file(path)) return nitf_image_info(read_nitf_image(path));
  if (is_tiff_file(path))
    if (auto info = tiff_image_info(path)) return *info;
  return oiio_image_info(path);
}

Raster read_region(const std::string& path, int band, long x0, long y0, long w, long h, Raster reuse) {
  check_input_file(path, InputKind::image);
  note_input(path);
  if (is_nitf_file(path)) return read_nitf_region(read_nitf_image(path), band, x0, y0, w, h);
  if (is_tiff_file(path))
    if (auto r = read_tiff_region(path, band, x0, y0, w, h, std::move(reuse))) return std::move(*r);
  return oiio_read_region(path, band, x0, y0, w, h);
}

std::vector<Raster> read_region_bands(const std::string& path, const std::vector<int>& bands, long x0, long y0, long w, long h,
                                      Raster reuse) {
  check_input_file(path, InputKind::image);  // before is_tiff_file opens it
  note_input(path);
  if (bands.size() > 1 && is_tiff_file(path))
    if (auto r = read_tiff_bands(path, bands, x0, y0, w, h, std::move(reuse))) return std::move(*r);
  std::vector<Raster> out;
  for (size_t j = 0; j < bands.size(); ++j) out.push_back(read_region(path, bands[j], x0, y0, w, h, j == 0 ? std::move(reuse) : Raster()));
  return out;
}

Raster clipped_raster(const std::string& path, long width, long height, int bands, int band, long x0, long y0, long w, long h,
                      Raster reuse) {
  if (band < 0 || band >= bands)
    throw InputError(path, 0, "band " + std::to_string(band + 1) + " does not exist (the image has " + std::to_string(bands) + ")");
  Raster r = std::move(reuse);
  r.x0 = std::max(0L, x0);
  r.y0 = std::max(0L, y0);
  r.width = std::max(0L, std::min(width, x0 + w) - r.x0);
  r.height = std::max(0L, std::min(height, y0 + h) - r.y0);
  const size_t n = static_cast<size_t>(r.width) * static_cast<size_t>(r.height);
  if (n > r.data.capacity()) r.data = std::vector<float>();  // larger than the memory given: fresh, not grown by a copy
  r.data.resize(n);
  return r;
}

Raster crop_region(const Raster& r, long x0, long y0, long w, long h) {
  Raster out;
  out.x0 = std::max(r.x0, x0);
  out.y0 = std::max(r.y0, y0);
  out.width = std::max(0L, std::min(r.x0 + r.width, x0 + w) - out.x0);
  out.height = std::max(0L, std::min(r.y0 + r.height, y0 + h) - out.y0);
  out.data.resize(static_cast<size_t>(out.width) * static_cast<size_t>(out.height));
  if (out.data.empty()) return out;  // nothing of r in the region (a zero width or height, as read_region gives)
  for (long y = 0; y < out.height; ++y)
    std::copy_n(r.data.data() + static_cast<size_t>(out.y0 - r.y0 + y) * static_cast<size_t>(r.width) + static_cast<size_t>(out.x0 - r.x0),
                out.width, out.data.data() + static_cast<size_t>(y) * static_cast<size_t>(out.width));
  return out;
}

Raster read_band(const std::string& path, int band) {
  ImageInfo info = image_info(path);
  return read_region(path, band, 0, 0, info.width, info.height);
}

struct TiffWriterU16::Impl {
  std::string path, tmp;
  long width = 0, height = 0, next_row = 0;
  std::unique_ptr<TiffRowWriter> out;
  bool closed = false;
};

namespace {
bool set_rpc_tag_in_place(const std::string& file, const std::array<double, 92>& values) {
  register_tiff_tags();
  TIFF* tif = TIFFOpen(file.c_str(), "r+");
  if (!tif) return false;
  int ok = TIFFSetField(tif, TIFFTAG_RPCCOEFFICIENT, static_cast<uint32_t>(92), values.data()) && TIFFRewriteDirectory(tif);
  TIFFClose(tif);
  return ok != 0;
}
}  // namespace

TiffWriterU16::TiffWriterU16(const std::string& path, long width, long height,
                             const std::vector<std::pair<std::string, std::string>>& tags)
    : impl_(new Impl) {
  impl_->path = path;
  claim_output(path);
  impl_->tmp = claim_temp(path);
  impl_->width = width;
  impl_->height = height;
  try {
    std::vector<std::pair<std::string, std::string>> all{{"Software", written_by()}};
    all.insert(all.end(), tags.begin(), tags.end());
    // deflate at its fastest level: on noisy 16-bit pixels level 6 (the default) saves 1.7 % of the bytes
    // for 4x the compression time (a 4096² tp-synth view: 22.14 against 22.52 MB, 2.0 against 0.46 s)
    impl_->out = std::make_unique<TiffRowWriter>(impl_->tmp, width, height, 16, 1, all);
  } catch (...) {
    impl_->out.reset();
    discard_temp(impl_->tmp);
    throw;
  }
}

TiffWriterU16::~TiffWriterU16() {
  if (!impl_->closed) {
    impl_->out.reset();
    discard_temp(impl_->tmp);
  }
}

void TiffWriterU16::write_rows(long y0, long rows, const uint16_t* data) {
  if (y0 != impl_->next_row) throw std::logic_error("TiffWriterU16: strips out of order");
  impl_->out->write_rows(rows, data);
  impl_->next_row = y0 + rows;
}

void TiffWriterU16::set_rpc_tag(const std::array<double, 92>& values) { impl_->out->set_rpc_tag(values); }

void TiffWriterU16::close() {
  if (impl_->closed) return;
  if (impl_->next_row != impl_->height) throw std::logic_error("TiffWriterU16: image not complete");
  if (!impl_->out->close()) throw InputError(impl_->path, 0, "write error (disk full?)");
  impl_->closed = true;
  finish_output(impl_->tmp, impl_->path);
}

namespace {
bool tiff_extension(const std::string& path) {
  const auto dot = path.rfind('.');
  if (dot == std::string::npos) return false;
  std::string ext = path.substr(dot + 1);
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return ext == "tif" || ext == "tiff";
}

void write_whole(const std::string& path, long width, long height, const void* data, size_t n, int bits) {
  if (static_cast<long>(n) != width * height) throw std::logic_error("write_image: size mismatch");
  claim_output(path);
  std::string tmp = claim_temp(path);  // keeps the extension last: OIIO picks the format from it
  try {
    if (tiff_extension(path)) {
      TiffRowWriter w(tmp, width, height, bits, 6, {{"Software", written_by()}});
      w.write_rows(height, data);
      if (!w.close()) throw InputError(path, 0, "write error (disk full?)");
    } else {
      oiio_write_image(tmp, path, width, height, bits, data);
    }
  } catch (...) {
    discard_temp(tmp);
    throw;
  }
  finish_output(tmp, path);
}
}  // namespace

void write_image_u8(const std::string& path, long width, long height, const std::vector<uint8_t>& data) {
  write_whole(path, width, height, data.data(), data.size(), 8);
}
void write_image_u16(const std::string& path, long width, long height, const std::vector<uint16_t>& data) {
  write_whole(path, width, height, data.data(), data.size(), 16);
}

std::optional<RpcTagValues> read_rpc_tag(const std::string& path) {
  check_input_file(path, InputKind::image);  // before libtiff, whose message would be "not a TIFF file" for them all
  register_tiff_tags();
  note_input(path);
  TIFF* tif = TIFFOpen(path.c_str(), "r");
  if (!tif) throw InputError(path, 0, "not a TIFF file (no RPC tag can be read)");
  uint32_t count = 0;
  double* v = nullptr;
  int ok = TIFFGetField(tif, TIFFTAG_RPCCOEFFICIENT, &count, &v);
  std::optional<RpcTagValues> out;
  if (ok) {
    if (count != 92 || !v) {
      TIFFClose(tif);
      throw InputError(path, 0, "RPC tag 50844 holds " + std::to_string(count) + " values instead of 92");
    }
    RpcTagValues r;
    std::copy(v, v + 92, r.begin());
    out = r;
  }
  TIFFClose(tif);
  if (out) {
    // libtiff converts a FLOAT array to the DOUBLE the tag was registered with, silently: the type on disk
    const auto entry = tiff_first_ifd_tag(path, TIFFTAG_RPCCOEFFICIENT);
    const int type = entry ? entry->type : 0;
    if (type != 0 && type != TIFF_DOUBLE)
      throw InputError(path, 0, "RPC tag 50844 is stored as " + std::string(type == TIFF_FLOAT ? "FLOAT" : "TIFF type " + std::to_string(type)) +
                                    ", not DOUBLE: its values have lost their precision (give the model in a sidecar or with --rpc)");
  }
  return out;
}

void copy_tiff_with_rpc_tag(const std::string& src, const std::string& dst, const RpcTagValues& values) {
  check_input_file(src, InputKind::image);
  note_input(src);
  claim_output(dst);
  std::string tmp = claim_temp(dst);
  auto fail = [&](const std::string& why) {
    discard_temp(tmp);
    throw InputError(dst, 0, why);
  };
  {
    std::FILE* in = std::fopen(src.c_str(), "rb");
    if (!in) {
      discard_temp(tmp);
      throw InputError(src, 0, "cannot open");
    }
    std::FILE* out = std::fopen(tmp.c_str(), "wb");
    if (!out) {
      std::fclose(in);
      fail("cannot create");
    }
    char buf[1 << 16];
    size_t n;
    bool ok = true;
    while ((n = std::fread(buf, 1, sizeof buf, in)) > 0) ok = ok && std::fwrite(buf, 1, n, out) == n;
    ok = ok && !std::ferror(in);
    std::fclose(in);
    ok = (std::fclose(out) == 0) && ok;
    if (!ok) fail("cannot copy " + src);
  }
  if (!set_rpc_tag_in_place(tmp, values)) {
    discard_temp(tmp);
    throw InputError(src, 0, "not a TIFF file, or its RPC tag 50844 cannot be written");
  }
  finish_output(tmp, dst);
}

void write_geotiff_grid(const std::string& path, const GeoGrid& g) {
  if (g.width <= 0 || g.height <= 0 || static_cast<long>(g.data.size()) != g.width * g.height)
    throw std::logic_error("write_geotiff_grid: size mismatch");
  register_tiff_tags();
  claim_output(path);
  std::string tmp = claim_temp(path);
  TIFF* tif = TIFFOpen(tmp.c_str(), "w");
  if (!tif) {
    discard_temp(tmp);
    throw InputError(path, 0, "cannot create");
  }
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(g.width));
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(g.height));
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 32);
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
  TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 16);
  TIFFSetField(tif, TIFFTAG_SOFTWARE, written_by().c_str());
  const double scale[3] = {g.dlon, g.dlat, 0};
  const double tie[6] = {0, 0, 0, g.lon0, g.lat0, 0};
  // GeoKeys: version 1.1.0, 4 keys: GTModelType = 2 (geographic), GTRasterType = 2 (PixelIsPoint),
  // GeographicType = 4326 (WGS 84), GeogAngularUnits = 9102 (degree)
  const uint16_t keys[] = {1, 1, 0, 4, 1024, 0, 1, 2, 1025, 0, 1, 2, 2048, 0, 1, 4326, 2054, 0, 1, 9102};
  bool ok = TIFFSetField(tif, 33550, 3, scale) && TIFFSetField(tif, 33922, 6, tie) &&
            TIFFSetField(tif, 34735, static_cast<int>(sizeof keys / sizeof keys[0]), keys);
  for (long y = 0; ok && y < g.height; ++y)
    ok = TIFFWriteScanline(tif, const_cast<float*>(g.data.data() + y * g.width), static_cast<uint32_t>(y), 0) == 1;
  TIFFClose(tif);
  if (!ok) {
    discard_temp(tmp);
    throw InputError(path, 0, "cannot write the GeoTIFF");
  }
  finish_output(tmp, path);
}

GeoGrid read_geotiff_grid(const std::string& path, const GeoBounds* within) {
  // georeferencing from the GeoTIFF tags, pixels through read_region
  check_input_file(path, InputKind::image);
  register_tiff_tags();
  note_input(path);
  TIFF* tif = TIFFOpen(path.c_str(), "r");
  if (!tif) throw InputError(path, 0, "not a TIFF file (a DEM must be a GeoTIFF)");
  auto doubles = [&](uint32_t tag, uint32_t n, double* out) {
    uint16_t count = 0;
    double* v = nullptr;
    if (!TIFFGetField(tif, tag, &count, &v) || !v || count < n) return false;
    std::copy(v, v + n, out);
    return true;
  };
  double scale[3], tie[6];
  bool geo = doubles(33550, 3, scale) && doubles(33922, 6, tie);
  std::map<int, int> keys;
  uint16_t nk = 0;
  uint16_t* k = nullptr;
  if (TIFFGetField(tif, 34735, &nk, &k) && k && nk >= 4)
    for (int e = 0; e < k[3] && 4 + 4 * e + 3 < nk; ++e)
      if (k[4 + 4 * e + 1] == 0) keys[k[4 + 4 * e]] = k[4 + 4 * e + 3];
  // GDAL's no-data value (tag 42113, ASCII): a sample equal to it is no height
  std::optional<double> nodata;
  char* nd = nullptr;
  if (TIFFGetField(tif, 42113, &nd) && nd) {
    std::string t(nd);
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    while (end && *end && std::isspace(static_cast<unsigned char>(*end))) ++end;
    if (end == t.c_str() || (end && *end)) {
      TIFFClose(tif);
      throw InputError(path, 0, "GDAL_NODATA tag 42113: '" + t + "' is not a number");
    }
    nodata = v;
  }
  TIFFClose(tif);
  if (!geo) throw InputError(path, 0, "no GeoTIFF georeferencing (ModelPixelScale and ModelTiepoint tags)");
  auto key = [&](int id, int def) { return keys.count(id) ? keys[id] : def; };
  int model = key(1024, 0), geog = key(2048, 0);
  if (model != 2 || geog != 4326)
    throw InputError(path, 0, "the DEM must be in geographic WGS 84 coordinates (EPSG:4326); GTModelType " +
                                  std::to_string(model) + ", GeographicType " + std::to_string(geog));
  if (!(scale[0] > 0) || !(scale[1] > 0)) throw InputError(path, 0, "ModelPixelScale must be positive");
  GeoGrid g;
  g.dlon = scale[0];
  g.dlat = scale[1];
  // the tie point maps raster (I, J) to (lon, lat); PixelIsArea (1, the default) puts raster (0, 0) at the
  // corner of the first sample, PixelIsPoint (2) at its centre
  double shift = key(1025, 1) == 2 ? 0.0 : 0.5;
  g.lon0 = tie[3] + (shift - tie[0]) * g.dlon;
  g.lat0 = tie[4] - (shift - tie[1]) * g.dlat;
  // the samples within the bounds (and two beyond, for interpolation), clipped to the grid: a DEM of a
  // country is not read whole for one scene, and a header declaring more samples than the file holds
  // fails on the part that is read
  const ImageInfo info = image_info(path);
  long x0 = 0, y0 = 0, x1 = info.width, y1 = info.height;
  if (within) {
    x0 = std::max(0L, static_cast<long>(std::floor((within->lon0 - g.lon0) / g.dlon)) - 2);
    x1 = std::min(info.width, static_cast<long>(std::ceil((within->lon1 - g.lon0) / g.dlon)) + 3);
    y0 = std::max(0L, static_cast<long>(std::floor((g.lat0 - within->lat1) / g.dlat)) - 2);
    y1 = std::min(info.height, static_cast<long>(std::ceil((g.lat0 - within->lat0) / g.dlat)) + 3);
    if (x1 <= x0 || y1 <= y0)
      throw InputError(path, 0, "the DEM (lon " + format_number(g.lon0) + " .. " + format_number(g.lon0 + (info.width - 1) * g.dlon) +
                                    ", lat " + format_number(g.lat0 - (info.height - 1) * g.dlat) + " .. " + format_number(g.lat0) +
                                    ") does not cover the scene (lon " + format_number(within->lon0) + " .. " +
                                    format_number(within->lon1) + ", lat " + format_number(within->lat0) + " .. " +
                                    format_number(within->lat1) + ")");
  }
  constexpr long kMaxSamples = 400L * 1000 * 1000;
  if ((x1 - x0) > kMaxSamples / std::max(1L, y1 - y0))
    throw InputError(path, 0, "the DEM window of " + std::to_string(x1 - x0) + " x " + std::to_string(y1 - y0) +
                                  " samples is larger than " + std::to_string(kMaxSamples) + " samples");
  Raster r = read_region(path, 0, x0, y0, x1 - x0, y1 - y0);
  g.lon0 += x0 * g.dlon;
  g.lat0 -= y0 * g.dlat;
  g.width = r.width;
  g.height = r.height;
  g.data = std::move(r.data);
  if (nodata)
    for (float& v : g.data)
      if (v == static_cast<float>(*nodata)) v = NAN;
  return g;
}

}  // namespace tpkit
