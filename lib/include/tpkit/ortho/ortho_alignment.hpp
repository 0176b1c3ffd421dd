// How well two orthos of one grid overlay: the shift between them measured tile by tile over the pixels
// valid in both (phase correlation for the whole-pixel part, then the enhanced correlation coefficient
// (OpenCV's ECC, translation only: insensitive to a gain and offset between dates) to a hundredth of a pixel),
// summarized by the median and its spread (NMAD) over the tiles.
//
// Convention: (dx, dy) is the shift of ortho B against ortho A in grid pixels (x = column, y = row): what A
// shows at grid pixel (x, y), B shows at (x + dx, y + dy). In metres: east = dx gsd, north = -dy gsd.
// Each ortho is seen as one grey image: the mean of its first three bands (one band: itself).
#pragma once
#include <string>
#include <vector>

#include "tpkit/ortho/ortho_geotiff.hpp"

namespace tpkit {

struct AlignmentOptions {
  long tile = 128;           // tile side, grid pixels (>= 32)
  double min_valid = 0.95;   // share of a tile's pixels valid in both orthos for it to be measured
  double min_ecc = 0.3;      // correlation (ECC) a tile must reach to count
  int threads = 1;
};

struct TileShift {
  double x = 0, y = 0;    // the tile's centre, grid pixels
  double dx = 0, dy = 0;  // pixels
  double ecc = 0;         // correlation reached
};

struct PairAlignment {
  long tiles_tried = 0;  // tiles with enough valid pixels in both
  std::vector<TileShift> tiles;  // those measured
  double dx = NAN, dy = NAN;          // medians over the tiles, pixels
  double nmad_dx = NAN, nmad_dy = NAN;  // 1.4826 x the median absolute deviation, pixels
};

// The grey image (float) of one ortho's tile; NaN at nodata. Exposed for the tests.
struct GreyTile {
  long width = 0, height = 0;
  std::vector<float> data;
};

// Shift of `b` against `a` from two grey tiles of one size (NaN samples are invalid); false when the tile has
// too few valid pixels, no texture, or the correlation does not converge.
bool measure_tile_shift(const GreyTile& a, const GreyTile& b, const AlignmentOptions& options, TileShift& out);

// Every tile of the two orthos' common grid (InputError naming a file when they are not on one grid).
PairAlignment measure_alignment(const std::string& a, const std::string& b, const AlignmentOptions& options);

}  // namespace tpkit
