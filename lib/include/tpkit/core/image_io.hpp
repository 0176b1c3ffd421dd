// Image reading and writing, whatever the format: TIFF/GeoTIFF through libtiff (tiff_image.hpp), NITF 2.1
// through nitf_image.hpp, every other format OpenImageIO reads (PNG, JPEG, ...) through its module
// (oiio_images.hpp); and the raw RPC tag 50844 of a GeoTIFF.
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
  // Bands 1 to 3 are red, green and blue: a TIFF whose photometric interpretation is RGB (libtiff's
  // default for 3 or more samples without the tag), a NITF whose IREP is RGB or RGB/LUT, a 3- or
  // 4-channel image of another format (PNG, JPEG: RGB or RGBA). Not a multispectral image's bands.
  bool rgb = false;
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

// The part of `r` in the region [x0, x0 + w) x [y0, y0 + h) (full-image pixels), clipped to r's extent:
// cut from a whole band, the raster read_region would return for the region.
Raster crop_region(const Raster& r, long x0, long y0, long w, long h);

// Reads band `band` (0-based) of the region, clipped to the image; values as float in the image's own
// radiometry (no scaling). Throws InputError for an unreadable file or a band that does not exist.
// `reuse`: a raster done with, whose samples' memory the TIFF reader fills in place of fresh memory (a
// band of a large image is tens of megabytes: fresh, each of its pages costs a fault and the kernel's
// and the vector's zeroing); the result is the same.
Raster read_region(const std::string& path, int band, long x0, long y0, long w, long h, Raster reuse = {});
// Several bands of the region, in the order asked for (`reuse`: the first's memory): a TIFF that
// interleaves its bands is decoded once for all of them, other files band by band.
std::vector<Raster> read_region_bands(const std::string& path, const std::vector<int>& bands, long x0, long y0, long w, long h,
                                      Raster reuse = {});
// Whole band.
Raster read_band(const std::string& path, int band = 0);
// For the readers: the raster of the region's part inside a width x height image (its samples
// allocated: zero, or in `reuse`'s memory whatever it held, for a reader that writes every sample),
// after checking that `band` is one of the image's `bands` (InputError naming `path`).
Raster clipped_raster(const std::string& path, long width, long height, int bands, int band, long x0, long y0, long w, long h,
                      Raster reuse = {});

// Writes a single-band 16-bit TIFF given strip of rows by strip of rows (bounded memory; the file is tiled
// as TiffRowWriter writes it), atomically: rows go to a temporary file that replaces `path` on close().
class TiffWriterU16 {
 public:
  TiffWriterU16(const std::string& path, long width, long height, const std::vector<std::pair<std::string, std::string>>& tags = {});
  ~TiffWriterU16();
  // Rows y0 .. y0 + rows - 1, each `width` samples; strips must come in order.
  void write_rows(long y0, long rows, const uint16_t* data);
  // Sets GeoTIFF tag 50844 (see RpcTagValues below) in the file written at close().
  void set_rpc_tag(const std::array<double, 92>& values);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Writes a whole 8-bit or 16-bit single-band image (TIFF through libtiff, other formats through OpenImageIO,
// by extension), atomically.
void write_image_u8(const std::string& path, long width, long height, const std::vector<uint8_t>& data);
void write_image_u16(const std::string& path, long width, long height, const std::vector<uint16_t>& data);

// GeoTIFF tag 50844 (RPCCoefficientTag): the 92 doubles of an RPC00B model as stored (ERR_BIAS, ERR_RAND,
// LINE_OFF, SAMP_OFF, LAT_OFF, LONG_OFF, HEIGHT_OFF, LINE_SCALE, SAMP_SCALE, LAT_SCALE, LONG_SCALE,
// HEIGHT_SCALE, then 20 each of LINE_NUM, LINE_DEN, SAMP_NUM, SAMP_DEN). The model itself, and what it
// means, is the rpc component's (rpc_model.hpp, rpc_io.hpp); here only the raw tag is read and written.
using RpcTagValues = std::array<double, 92>;
// Nothing when the tag is absent. Throws InputError for a file that is not a TIFF or a tag of another length.
std::optional<RpcTagValues> read_rpc_tag(const std::string& path);
// Writes a copy of the TIFF `src` (pixels and every other tag kept) with tag 50844 set, atomically.
void copy_tiff_with_rpc_tag(const std::string& src, const std::string& dst, const RpcTagValues& values);

// A height grid on geographic coordinates (a DEM): single band, heights in metres; sample (i, j) (column i,
// row j) stands at lon = lon0 + i * dlon, lat = lat0 - j * dlat (degrees WGS84, dlon, dlat > 0; the sample
// is the value at that point, GeoTIFF PixelIsPoint). NaN = no data.
struct GeoGrid {
  long width = 0, height = 0;
  double lon0 = 0, lat0 = 0, dlon = 1, dlat = 1;
  std::vector<float> data;  // row-major
};
// Writes a float32 GeoTIFF (EPSG:4326, PixelIsPoint: ModelPixelScale, ModelTiepoint and GeoKeyDirectory
// through libtiff), atomically.
void write_geotiff_grid(const std::string& path, const GeoGrid& grid);
// Reads a single-band GeoTIFF, its georeferencing from the GeoTIFF tags
// (ModelPixelScale, ModelTiepoint; geographic WGS84 only, PixelIsArea converted to sample
// centres). InputError for a file without them or in another coordinate system.
// Samples equal to the GDAL_NODATA tag (42113) are NaN. With `within`, only the samples covering those
// bounds (two more on each side) are read; InputError when the grid does not reach them.
struct GeoBounds {
  double lon0, lon1, lat0, lat1;  // degrees, lon0 < lon1, lat0 < lat1
};
GeoGrid read_geotiff_grid(const std::string& path, const GeoBounds* within = nullptr);

}  // namespace tpkit
