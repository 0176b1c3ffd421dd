// TIFF and GeoTIFF images read and written through libtiff directly: the format of nearly every
// satellite product and of every image tpkit writes. Other formats go through OpenImageIO
// (oiio_images.hpp), which Debian builds against some 250 libraries (codecs, GDAL, OpenVDB, ...):
// loading them costs about 0.37 s at every process start, more than tp-match needs to match a small
// pair, so tools load it only when a file needs it.
//
// Pixel convention: x = column, y = row, (0, 0) the centre of the top-left pixel. Regions are whole
// pixels [x0, x0 + w) x [y0, y0 + h), clipped to the image, and only the strips or tiles that meet
// them are decoded. Samples are converted to float without scaling (a 12-bit range in 16-bit words
// stays 0..4095).
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tpkit/core/image_io.hpp"

namespace tpkit {

// True when the file starts like a classic or Big TIFF (byte order mark and 42 or 43).
bool is_tiff_file(const std::string& path);

// The entry of `tag` in the first directory (IFD) of a classic or Big TIFF as the file writes it: its field
// type (TIFF type code: 11 FLOAT, 12 DOUBLE, ...), its count, and where its values lie (in the entry
// itself when they fit); nothing when the directory has no such tag or cannot be read. libtiff passes
// over a tag whose values it cannot read (a count that runs past the end of the file) as if it were
// absent, and converts a FLOAT array to the DOUBLE it was registered with: this reads what is on disk.
struct TiffTagEntry {
  int type = 0;
  uint64_t count = 0;
  uint64_t offset = 0, bytes = 0;  // the values' byte range (bytes 0: a type not known here)
};
std::optional<TiffTagEntry> tiff_first_ifd_tag(const std::string& path, uint16_t tag);

// The image's size, bands, sample type ("uint8", "int8", "uint16", "int16", "uint32", "int32", "float",
// "double"), bits per sample and GDAL_NODATA value; nothing when the file is a TIFF whose layout this
// reader leaves to OpenImageIO (palette, YCbCr, bit-packed or half-float samples, ...). InputError for
// a file libtiff cannot open.
std::optional<ImageInfo> tiff_image_info(const std::string& path);

// Band `band` (0-based) of the region; nothing under the same condition as tiff_image_info. InputError
// for a missing band, a strip or tile beyond the end of the file (a truncated file, or a header that
// declares more samples than the file holds: refused before anything that size is allocated) and a
// chunk that cannot be decoded. `reuse` as read_region's.
std::optional<Raster> read_tiff_region(const std::string& path, int band, long x0, long y0, long w, long h, Raster reuse = {});
// Several bands of the region, in the order asked for (reuse: the first's memory), each chunk decoded
// once for all of them when the file interleaves the bands; otherwise as read_tiff_region.
std::optional<std::vector<Raster>> read_tiff_bands(const std::string& path, const std::vector<int>& bands, long x0, long y0, long w,
                                                   long h, Raster reuse = {});

// libtiff's field definitions for the tags tpkit reads and writes beyond the baseline: RPC tag 50844,
// the GeoTIFF tags and GDAL_NODATA; libtiff's own warnings silenced (errors are reported by the callers).
void register_tiff_tags();

// A single-band 8- or 16-bit TIFF written row by row to `path` (deflate at `zip_level`, horizontal
// predictor, 256 x 256 tiles: a reader of a block decodes that block's tiles, where full-width strips
// made a job reading a quarter of a 10000-px row decode four times its pixels; the writer holds one row
// of tiles, 256 rows). `tags` are TIFF ASCII tags by name: ImageDescription, DateTime, Software,
// Artist, Copyright, DocumentName. The file is written as given: atomicity is the caller's.
class TiffRowWriter {
 public:
  TiffRowWriter(const std::string& path, long width, long height, int bits, int zip_level,
                const std::vector<std::pair<std::string, std::string>>& tags);
  ~TiffRowWriter();
  TiffRowWriter(const TiffRowWriter&) = delete;
  TiffRowWriter& operator=(const TiffRowWriter&) = delete;
  // `rows` rows of `width` samples of `bits` bits each, in order from the top.
  void write_rows(long rows, const void* data);
  // Sets tag 50844 (written at close).
  void set_rpc_tag(const std::array<double, 92>& values);
  // Flushes and closes; false on a write error.
  bool close();

 private:
  void* tif_ = nullptr;
  std::string path_;
  long width_, height_, next_ = 0;
  int bits_;
  static constexpr long kTile = 256;
  std::vector<unsigned char> band_, tile_;  // the current row of tiles; one tile being encoded
  void write_tile_row();
};

}  // namespace tpkit
