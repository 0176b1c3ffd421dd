// Descriptor matching guided by the epipolar geometry of two satellite views (image 1 -> image 2).
//
// 1. Coarse: the strongest keypoints of each image, spread over a coarse_grid x coarse_grid grid
//    (at most `coarse_keypoints` per image), are matched globally (match_descriptors: ratio test,
//    mutual check) and an affine fundamental matrix F is fitted by RANSAC. For affine views every
//    epipolar line in image 2 has the same direction u2 (unit normal n2 = (a, b) / |(a, b)| of F), and
//    a point x1 maps to x2 = (affine function of x1) + lambda u2, lambda the parallax, which depends on
//    the height of the ground point. The along-line coordinate s2 = u2 . x2 of the coarse inliers is
//    fitted by a plane s2 ~ g(x1); the residuals are their parallaxes. Each coarse cell of image 1 gets
//    the parallax range of the inliers in it and its eight neighbours (or of all of them when fewer
//    than `min_cell_samples`), widened by `parallax_margin` pixels.
// 2. Guided: every keypoint x1 is compared only with the image-2 keypoints in its search region,
//    the band |n2 . x2 - d(x1)| <= band around its epipolar line and s2 - g(x1) within its cell's
//    parallax range. The best candidate must lie there; the ratio test compares it with the second
//    nearest descriptor in a region `ratio_margin` pixels wider on every side, and the mutual check
//    asks that x1 be the nearest of all image-1 keypoints whose wider region holds x2. Descriptor
//    distances are exact L2 (integers on the 8-bit SIFT descriptors).
// The cost is the number of keypoints times the keypoints of image 2 per search region, not the
// product of the two sets, and no float copy or search index of the descriptors is built: memory is
// the descriptors themselves. Deterministic for any thread count.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "tpkit/match/affine_fundamental.hpp"
#include "tpkit/match/match_descriptors.hpp"
#include "tpkit/match/sift_tiles.hpp"

namespace tpkit {

// The search region of one image-1 keypoint in image 2, pixels: the rectangle of the points x2 with
// |n . (x2 - a)| <= band and 0 <= u . (x2 - a) <= length, u a unit vector, n = (u.y, -u.x) (a
// segment of the keypoint's epipolar line or curve, from a, widened by band on both sides).
// length < 0: the keypoint has no region and is not matched.
struct SearchRegion {
  Eigen::Vector2d a{0, 0}, u{1, 0};
  double length = -1, band = 0;
};

struct RegionMatchResult {
  std::vector<DescriptorMatch> matches;  // rows of K1.desc / K2.desc, sorted by i1
  double candidates_per_query = 0;       // mean descriptors compared per image-1 keypoint
};

// Stage 2 of the guided search for any geometry (the affine one below, or RPC epipolar curves,
// rpc_guided_matching.hpp): keypoint i of K1 is compared only with the keypoints of K2 in regions[i];
// the best must lie there, the ratio test compares it with the second nearest in the region
// `ratio_margin` pixels wider on every side, and the mutual check asks that i be the nearest of all
// image-1 keypoints whose wider region holds it. Exact L2 on the 8-bit descriptors; deterministic for
// any thread count. regions.size() == K1.kp.size().
RegionMatchResult match_in_regions(const Keypoints& K1, const Keypoints& K2, const std::vector<SearchRegion>& regions,
                                   const DescriptorMatchOptions& desc, double ratio_margin, int threads);

// Indices (ascending) of the strongest keypoints (response), at most total / grid^2 per cell of a
// grid x grid split of their extent: the keypoints of a coarse stage.
std::vector<int> strongest_spread(const std::vector<cv::KeyPoint>& kp, int total, int grid);

// The range of a value sampled at image-1 positions (x, y, value), per cell of a grid x grid split of
// a w x h image: over the cell and its eight neighbours, or over all samples where those hold fewer
// than min_samples; widened by margin at both ends. xyv must not be empty.
struct CellRanges {
  int grid = 1;
  long w = 1, h = 1;
  std::vector<double> lo, hi;  // per cell, row-major
  size_t cell(double x, double y) const;
};
CellRanges cell_ranges(const std::vector<Eigen::Vector3d>& xyv, long w, long h, int grid, int min_samples, double margin);

struct GuidedMatchOptions {
  int coarse_keypoints = 2000;   // strongest keypoints per image used by the coarse match (4000: same
                                 // matches on the Pleiades pairs, 0.09 s more per pair)
  int coarse_grid = 8;           // cells per side over which they are spread (and parallax ranges kept)
  int min_cell_samples = 8;      // coarse inliers needed around a cell for its own parallax range
  double band = 2.0;             // pixels across the epipolar line
  double parallax_margin = 8.0;  // pixels added to each end of a cell's parallax range
  double ratio_margin = 64.0;    // pixels: the region of the ratio test and the mutual check is wider
};

struct GuidedMatchResult {
  bool ok = false;                       // false: the coarse stage found no epipolar geometry
  AffineFundamental F;                   // from the coarse inliers
  long coarse_putative = 0, coarse_inliers = 0;
  double parallax_min = 0, parallax_max = 0;  // over the coarse inliers, pixels along u2
  double candidates_per_query = 0;       // mean descriptors compared per image-1 keypoint
  std::vector<DescriptorMatch> matches;  // rows of K1.desc / K2.desc, sorted by i1
};

// K1.kp / K2.kp positions in full-image pixels, desc CV_8U n x 128. w1 x h1: image 1's size.
// `ransac`: the coarse F fit; `min_inliers`: fewer coarse inliers = not ok (the caller falls back).
GuidedMatchResult guided_match(const Keypoints& K1, const Keypoints& K2, long w1, long h1,
                               const DescriptorMatchOptions& desc, const GuidedMatchOptions& g,
                               const AffineFundamentalRansac& ransac, int min_inliers, int threads);

}  // namespace tpkit
