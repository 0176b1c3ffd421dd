// SIFT keypoints of one image band, found tile by tile (sift_scale_space.hpp) on an 8-bit
// percentile-stretched rendering (image_tiles.hpp), with stable ids and RootSIFT descriptors (root_sift.hpp). Positions are in the full
// image's pixels (x = column, y = row, (0, 0) the centre of the top-left pixel). Memory is bounded by one band of tiles (a tile row, full width) and one tile per worker plus the
// keypoints and their 128-byte descriptors.
//
// Ids: id = t * kIdsPerTile + r, t the index of the detection tile (tile_grid over the whole image,
// row-major) that owns the keypoint and r its rank in that tile by (y, x, size, angle, response,
// octave). The grid depends on the image size and the options only, and a tile's keypoints on its own
// read region only, so the same image, band, nodata/mask and SiftOptions give the same ids whatever
// the thread count and whatever part of the image a run detects (tp-match --region): tiles' outputs
// join (detector_tag() records the options in the matches header; tp-chain joins files by these ids).
// The keypoints of a run are sorted by (y, x, ...) band of tiles by band.
#pragma once
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "tpkit/match/image_tiles.hpp"

namespace tpkit {

struct SiftOptions {
  long tile = 1024;           // tile core size in pixels (tile_grid)
  long overlap = 96;          // margin read around each core; keypoints larger than it are dropped
  int max_per_tile = 0;       // strongest keypoints kept per tile (0 = all)
  double contrast = 0.02;     // OpenCV contrastThreshold (on the 8-bit rendering)
  // OpenCV edgeThreshold (the largest ratio of principal curvatures kept). 14, not Lowe's 10: the
  // least-squares matching places an elongated blob in both coordinates and reports its precision.
  // With RootSIFT, 1024² tp-synth pairs gain 6-27% correct matches at the same error (a scene 30% water
  // 5289 -> 6164; at 16: 6429) and Marseille 7268 -> 7690 triplets at an ML fit RMSE of 0.0977 px on the
  // robust fit's inliers (0.0971 at 10, 0.0985 at 16, 0.1012 at 20).
  double edge = 14;
  double sigma = 1.6;
  int octave_layers = 3;
  double stretch_lo = 0.5, stretch_hi = 99.5;  // percentiles of the 8-bit rendering
};

struct Keypoints {
  std::vector<cv::KeyPoint> kp;  // kp[i].pt in full-image pixels
  cv::Mat desc;                  // n x 128, CV_8U: RootSIFT (root_sift.hpp)
  std::vector<long long> id;     // stable ids (see above)
  Stretch stretch;
  long tiles = 0;
};

// The scale-space options of the detector (sift_scale_space.hpp) that SiftOptions sets.
struct ScaleSpaceOptions;
ScaleSpaceOptions scale_space_options(const SiftOptions& o);

// Text for the matches header naming the detector and every option that changes the ids.
std::string detector_tag(const SiftOptions& o, const ImageSource& src);

// How many SIFT calls (tiles, images) run at once with `threads` threads: one per two threads, at least
// one. OpenCV parallelises inside each call on its own pool (opencv_threads.hpp; about 1.6x on two
// threads), and a tile detected after another of its size reuses that one's pyramid memory
// (opencv_memory.hpp), where calls side by side each map theirs afresh. 2 threads, 16 tiles of a
// 10000² view (--detect 1 --region 0 0 3072 3072): 22.1 -> 19.8 s, 733 -> 405 MB, 2.0 -> 0.5 s system
// time against two tiles at a time.
int concurrent_sift_calls(int threads);

// Detects keypoints over the whole image with `threads` threads (concurrent_sift_calls tiles at a
// time); `progress` (may be null) is advanced once per tile.
class Progress;
Keypoints detect_sift_tiles(const ImageSource& src, const SiftOptions& o, int threads, Progress* progress = nullptr);

constexpr long long kIdsPerTile = 100000000;  // ids of tile t are t * kIdsPerTile + rank

// The tiles of `grid` whose core meets the window [x0, x1) x [y0, y1) (pixel-centre coordinates).
std::vector<Tile> tiles_meeting(const std::vector<Tile>& grid, double x0, double y0, double x1, double y1);
// The tiles of `grid` whose core starts (top-left pixel cx0, cy0) in the window [x0, x0 + w) x
// [y0, y0 + h) of whole pixels: windows that partition an image partition its tiles.
std::vector<Tile> tiles_starting_in(const std::vector<Tile>& grid, long x0, long y0, long w, long h);

// Detection of some tiles of the global grid (tile_grid(width, height, o.tile, o.overlap)) with a given
// stretch (percentile_stretch of the whole image, as detect_sift_tiles computes it): the keypoints and
// ids a whole-image run finds in these tiles. Reads only the tiles' regions (band of tiles by band).
Keypoints detect_sift_tile_set(const ImageSource& src, const SiftOptions& o, const Stretch& st, const std::vector<Tile>& tiles,
                               int threads, Progress* progress = nullptr);
// The two halves of it: each tile's keypoints in rank order with their ids (one entry per tile), and
// their gathering into one set in the stable order (tiles in grid order).
std::vector<Keypoints> detect_tiles_ranked(const ImageSource& src, const SiftOptions& o, const Stretch& st,
                                           const std::vector<Tile>& tiles, int threads, Progress* progress = nullptr);
Keypoints gather_tiles(std::vector<Keypoints> per_tile, const std::vector<Tile>& tiles, const Stretch& st);

}  // namespace tpkit
