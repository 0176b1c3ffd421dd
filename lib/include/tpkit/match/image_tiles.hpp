// An image as tp-match sees it: one grey level per pixel (one band, or a weighted sum of bands: the
// luminance of an RGB image) in the original radiometry as float, with invalid pixels (nodata value,
// zero in a mask image) set to NaN, an 8-bit rendering by a robust percentile stretch for the detector,
// and a grid of overlapping tiles so that large images are read region by region.
// Pixels: x = column, y = row, (0, 0) the centre of the top-left pixel; regions in whole pixels.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tpkit/core/image_io.hpp"

namespace tpkit {

struct ImageSource {
  std::string path;
  // The grey level read: the sum of weights[k] x band k (0-based) over the bands; a band of weight 0
  // is not read. One band: a single weight of 1.
  std::vector<float> weights;
  // The rendering as the detector line names it (so that a keypoint cache or pair geometry made from
  // another rendering is not reused): "band=2", "luminance=0.299R+0.587G+0.114B", "mean=bands1-8".
  std::string rendering;
  std::optional<double> nodata;   // pixels equal to it are invalid (default: the file's GDAL_NODATA tag)
  std::string mask;               // optional mask image of the same size: 0 = invalid
  ImageInfo info;                 // filled by open_image_source()
};

// Checks the file, the band and the mask, and fills `info` and the rendering: band `band` (0-based)
// when given, else the image's default (default_rendering); takes the file's nodata tag when `nodata`
// is unset. Throws InputError (path: reason) for an unreadable file, a missing band or a mask of
// another size.
ImageSource open_image_source(const std::string& path, std::optional<int> band, std::optional<double> nodata,
                              const std::string& mask);

// The weights and name of an image's default rendering: its band for a single-band image; for an RGB
// image (ImageInfo::rgb) the luminance 0.299 R + 0.587 G + 0.114 B of bands 1 to 3 (further bands,
// such as an alpha channel, are not read); for another multi-band image (multispectral: bands that are
// not colours of a display) the mean of all bands.
void default_rendering(const ImageInfo& info, std::vector<float>& weights, std::string& rendering);

// Region [x0, x0 + w) x [y0, y0 + h) clipped to the image, as float, invalid pixels NaN (a pixel is
// invalid when any band read is nodata). `reuse` as read_region's. A rendering of several bands reads
// them together (read_region_bands), a raster of the region's size for each.
Raster read_valid_region(const ImageSource& src, long x0, long y0, long w, long h, Raster reuse = {});

// Grey levels at the low and high percentiles (0..100) of the valid pixels, from a regular subsample
// of at most ~`max_samples` pixels read strip by strip (bounded memory: a strip of 4 M pixels per
// worker, min(threads, 4) workers). lo == hi when the image is flat; throws InputError when no pixel is
// valid.
struct Stretch {
  double lo = 0, hi = 1;
  long valid_samples = 0;
};
constexpr long kStretchSamples = 1 << 21;
Stretch percentile_stretch(const ImageSource& src, double p_lo = 0.5, double p_hi = 99.5, long max_samples = kStretchSamples,
                           int threads = 1);

// percentile_stretch's stages, for a caller that reads the whole image for another purpose as well
// (pair_geometry.cpp: its decimated copy) and samples it on the way: the subsample step (every
// step-th pixel of every step-th row, counted from the image's origin); the samples of a strip of
// whole rows (strip.y0 its first row), appended; the percentiles of the samples gathered, in any order.
long stretch_step(long width, long height, long max_samples = kStretchSamples);
void add_stretch_samples(const Raster& strip, long step, std::vector<float>& samples);
Stretch stretch_of_samples(std::vector<float> samples, double p_lo, double p_hi, const ImageSource& src);

// 8-bit rendering: round(255 (v - lo) / (hi - lo)) clipped to 0..255; NaN (invalid) -> 0.
// `valid` (same size, may be null) receives 255 for valid pixels, 0 otherwise.
std::vector<uint8_t> render_u8(const Raster& r, const Stretch& s, std::vector<uint8_t>* valid = nullptr);
// The same for the window [x0, x0 + w) x [y0, y0 + h) of r (full-image pixels, within r), row-major.
std::vector<uint8_t> render_u8(const Raster& r, long x0, long y0, long w, long h, const Stretch& s,
                               std::vector<uint8_t>* valid = nullptr);

// A tile: the core [cx0, cx1) x [cy0, cy1) that owns the features found in it, and the read region
// [rx0, rx1) x [ry0, ry1) = core grown by `overlap` on every side, clipped to the image.
struct Tile {
  int index = 0;
  long cx0 = 0, cy0 = 0, cx1 = 0, cy1 = 0;
  long rx0 = 0, ry0 = 0, rx1 = 0, ry1 = 0;
};
// Row-major grid of round(width / tile) x round(height / tile) tiles (at least 1 x 1) with cores of
// nearly equal size (so at most about 1.5 tile on a side) covering width x height.
std::vector<Tile> tile_grid(long width, long height, long tile, long overlap);

}  // namespace tpkit
