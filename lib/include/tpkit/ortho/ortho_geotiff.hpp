// Orthoimages as GeoTIFF files: tiled (256 x 256), deflate-compressed (horizontal predictor for integer
// samples), pixel-interleaved, every band of the source in its sample type, the grid's CRS and extent in the
// GeoTIFF keys (libgeotiff: ProjectedCSTypeGeoKey = the EPSG code, RasterPixelIsArea, ModelTiepoint at the
// grid's top-left corner, ModelPixelScale gsd), nodata in GDAL's tag 42113. BigTIFF above 3 GiB of samples.
// Tiles are compressed by the thread that made them (zlib) and only their writing is serialized, so the
// writer scales with the threads of orthorectify().
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tpkit/ortho/ortho_grid.hpp"

namespace tpkit {

// Sample types written: the source image's (core/image_io.hpp ImageInfo::format names).
enum class SampleType { u8, u16, i16, u32, i32, f32, f64 };
// "uint8" -> u8, ... "float" -> f32, "double" -> f64; InputError naming `path` for any other.
SampleType sample_type_of(const std::string& format, const std::string& path);
int sample_bytes(SampleType t);
// The value a sample of type t holds for v: rounded to the nearest integer and clamped to the type's range
// for integer types (bicubic overshoots), as is for floating point.
double to_sample(SampleType t, double v);

struct OrthoTiffLayout {
  OrthoGrid grid;
  int bands = 1;
  SampleType type = SampleType::u8;
  bool rgb = false;         // bands 1-3 are red, green, blue (photometric RGB)
  double nodata = 0;        // written in GDAL_NODATA (NaN: "nan")
  std::string description;  // ImageDescription (what the ortho is)
  static constexpr long kTile = 256;
  long tiles_across() const { return (grid.width + kTile - 1) / kTile; }
  long tiles_down() const { return (grid.height + kTile - 1) / kTile; }
};

// Writes the file through a temporary one (atomic_output.hpp: it becomes `path` at commit, none is left on
// failure). write_tile may be called from any thread, in any order, once for every tile.
class OrthoTiffWriter {
 public:
  OrthoTiffWriter(const std::string& path, const OrthoTiffLayout& layout);
  ~OrthoTiffWriter();
  OrthoTiffWriter(const OrthoTiffWriter&) = delete;
  OrthoTiffWriter& operator=(const OrthoTiffWriter&) = delete;
  // The tile (tx, ty): kTile x kTile pixels x bands, interleaved (sample b of pixel (c, r) at
  // (r * kTile + c) * bands + b), each sample_bytes(type) bytes in the machine's order; modified in place
  // (predictor).
  void write_tile(long tx, long ty, std::vector<unsigned char>& samples);
  // Closes the file and hands it over (finish_output); InputError when a tile is missing or a write failed.
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// What an ortho's GeoTIFF says of its grid (for --like and --compare): a projected CRS named by its EPSG
// code, square pixels, no rotation. InputError naming `path` otherwise.
struct OrthoFileInfo {
  OrthoGrid grid;
  int bands = 0;
  bool has_nodata = false;
  double nodata = 0;
};
OrthoFileInfo read_ortho_info(const std::string& path);

}  // namespace tpkit
