// Image reading and writing through OpenImageIO (every format it reads: TIFF/GeoTIFF, PNG, ...), and
// the RPC camera model of GeoTIFF tag 50844 through libtiff (the one thing OIIO does not expose).
// Pixel convention: x = column, y = row, (0, 0) the centre of the top-left pixel. Regions are given in
// whole pixels [x0, x0 + w) x [y0, y0 + h) and are read without loading the rest of the image.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tpkit {

struct ImageInfo {
  std::string path;
  long width = 0, height = 0;
  int bands = 0;
  std::string format;  // "uint8", "uint16", "float", ...
  int bits = 0;        // bits per sample as stored (e.g. 12 for a 12-bit range in 16-bit words, when tagged)
  std::optional<double> nodata;  // from the GDAL_NODATA tag, when present
};

// Throws InputError(path: reason) when the file is not a readable image.
ImageInfo image_info(const std::string& path);

// A single-band float raster, row-major: at(x, y) = data[y * width + x].
struct Raster {
  long x0 = 0, y0 = 0;  // position of data[0] in the full image
  long width = 0, height = 0;
  std::vector<float> data;
  float at(long x, long y) const { return data[static_cast<size_t>(y) * width + x]; }
  float& at(long x, long y) { return data[static_cast<size_t>(y) * width + x]; }
};

// Reads band `band` (0-based) of the region, clipped to the image; values as float in the image's own
// radiometry (no scaling). Throws InputError for an unreadable file or a band that does not exist.
Raster read_region(const std::string& path, int band, long x0, long y0, long w, long h);
// Whole band.
Raster read_band(const std::string& path, int band = 0);

// Writes a single-band 16-bit TIFF row strip by row strip (bounded memory), atomically: rows go to a
// temporary file that replaces `path` on close().
class TiffWriterU16 {
 public:
  TiffWriterU16(const std::string& path, long width, long height, const std::vector<std::pair<std::string, std::string>>& tags = {});
  ~TiffWriterU16();
  // Rows y0 .. y0 + rows - 1, each `width` samples; strips must come in order.
  void write_rows(long y0, long rows, const uint16_t* data);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Writes a whole 8-bit or 16-bit single-band image (PNG/TIFF by extension), atomically.
void write_image_u8(const std::string& path, long width, long height, const std::vector<uint8_t>& data);
void write_image_u16(const std::string& path, long width, long height, const std::vector<uint16_t>& data);

// Rational polynomial camera (RPC00B), from GeoTIFF tag 50844 (92 doubles).
struct Rpc {
  double err_bias = 0, err_rand = 0;
  double line_off = 0, samp_off = 0, lat_off = 0, lon_off = 0, height_off = 0;
  double line_scale = 1, samp_scale = 1, lat_scale = 1, lon_scale = 1, height_scale = 1;
  std::array<double, 20> line_num{}, line_den{}, samp_num{}, samp_den{};
  // Ground (longitude, latitude in degrees, height in metres above the ellipsoid) to image (x, y) in
  // tpkit pixels. RPC00B line/sample are taken with (0, 0) at the centre of the top-left pixel, as in
  // the data this project uses; conversion to other conventions happens here only.
  std::array<double, 2> project(double lon, double lat, double h) const;
  // Inverse at a given height: the (longitude, latitude) in degrees whose projection is pixel (x, y),
  // by Gauss-Newton on project(); throws NumericalError when it does not converge.
  std::array<double, 2> localize(double x, double y, double h) const;
};

// The RPC of a TIFF file, or nothing when the tag is absent. Throws InputError for a malformed tag.
std::optional<Rpc> read_rpc(const std::string& path);

}  // namespace tpkit
