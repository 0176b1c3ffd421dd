// SIFT keypoints of one image band, found tile by tile on an 8-bit percentile-stretched rendering
// (image_tiles.hpp), with stable ids. Positions are in the full image's pixels (x = column, y = row,
// (0, 0) the centre of the top-left pixel). Memory is bounded by one band of tiles (a tile row, full width) and one tile per worker plus the
// keypoints and their 128-byte descriptors.
//
// Ids: keypoints are sorted by (y, x, size, angle, response) and numbered from 0, so the same image,
// band, nodata/mask and SiftOptions give the same ids whatever the thread count (detector_tag()
// records the options in the matches header; tp-chain joins files by these ids).
#pragma once
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "tpkit/image_tiles.hpp"

namespace tpkit {

struct SiftOptions {
  long tile = 1024;           // tile core size in pixels (tile_grid)
  long overlap = 96;          // margin read around each core; keypoints larger than it are dropped
  int max_per_tile = 0;       // strongest keypoints kept per tile (0 = all)
  double contrast = 0.02;     // OpenCV contrastThreshold (on the 8-bit rendering)
  double edge = 10;           // OpenCV edgeThreshold
  double sigma = 1.6;
  int octave_layers = 3;
  double stretch_lo = 0.5, stretch_hi = 99.5;  // percentiles of the 8-bit rendering
};

struct Keypoints {
  std::vector<cv::KeyPoint> kp;  // kp[i].pt in full-image pixels
  cv::Mat desc;                  // n x 128, CV_8U (OpenCV SIFT's descriptors are integers 0..255)
  std::vector<long long> id;     // stable ids, here equal to the index
  Stretch stretch;
  long tiles = 0;
};

// Text for the matches header naming the detector and every option that changes the ids.
std::string detector_tag(const SiftOptions& o, const ImageSource& src);

// Detects keypoints over the whole image with `threads` workers; `progress` (may be null) is
// advanced once per tile.
class Progress;
Keypoints detect_sift_tiles(const ImageSource& src, const SiftOptions& o, int threads, Progress* progress = nullptr);

}  // namespace tpkit
