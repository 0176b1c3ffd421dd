// A region run of tp-match (--region X0 Y0 W H): the matches of the image-1 keypoints inside the window
// [X0, X0 + W) x [Y0, Y0 + H) of image-1 pixels (pixel-centre coordinates: a keypoint at x belongs to
// the window when X0 - 0.5 <= x < X0 + W - 0.5, as detection tiles own their keypoints), such that a
// pair split into regions gives, once merged (matches_merge.hpp), the whole run's matches.
//
// - Image 1: the detection tiles of the global grid (sift_tiles.hpp) that meet the window grown by
//   `margin` pixels are detected with the whole image's stretch (from the pair geometry): keypoints
//   and ids are exactly those of a whole run. The keypoints of the grown window are all matched, so
//   that the ratio test, the mutual check and RANSAC see the same neighbourhood as a whole run for the
//   keypoints of the window; only those in the window are refined and written.
// - Image 2: only the tiles that meet image2_window() of the grown window (the coarse map of the pair
//   geometry, grown by its spread and `margin`) are read and detected.
// - Then the pipeline of match_keypoints() (guided search with its own coarse stage on these keypoints,
//   affine F RANSAC, refinement) as a whole run.
// Memory and time grow with the window (plus margins and the parallax spread), not with the images.
// Differences from a whole run come from the RANSAC fits and the coarse stage seeing only the region:
// they concern matches near the acceptance thresholds, most of them within the margin of the window's
// borders.
#pragma once
#include <array>

#include "tpkit/match/match_pair.hpp"
#include "tpkit/match/pair_geometry.hpp"

namespace tpkit {

struct RegionOptions {
  std::array<long, 4> window{0, 0, 0, 0};  // X0 Y0 W H, image-1 pixels
  // pixels (image 1 and image 2) matched beyond the window. On the 10000² tp-synth pair, a 2500² region
  // gave 99.90-99.91% of its records equal to the whole run's at 256, 192, 128 and 96 px; at 128 instead of
  // 256 it matches 170 626 image-1 keypoints instead of 202 538, in 3.8 s instead of 4.2 s.
  double margin = 128;
};

struct RegionStats {
  long tiles1 = 0, tiles2 = 0;          // detection tiles read
  long cached_tiles1 = 0, cached_tiles2 = 0;
  std::array<double, 4> window2{0, 0, 0, 0};  // image-2 window x0 y0 x1 y1, clipped
  long matched = 0;                     // verified matches of the grown window, before keeping those of the window
};

// Throws UsageError when the window is empty or outside image 1.
Matches match_region(const ImageSource& a, const ImageSource& b, const PairGeometry& G, const PairMatchOptions& o,
                     const RegionOptions& r, PairMatchStats* stats = nullptr, RegionStats* rstats = nullptr);

}  // namespace tpkit
