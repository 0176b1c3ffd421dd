// RPC-guided matching (image 1 -> image 2): where each image-1 keypoint can match comes from the two
// images' RPC models instead of a coarse stage on the image content.
//
// The ground point seen at pixel x1 of image 1 lies on its line of sight; between heights h_lo and h_hi
// (metres above the WGS84 ellipsoid) that line projects into image 2 as the epipolar curve of x1
// (rpc_model.hpp, epipolar_curve). A search region (guided_matching.hpp) is the chord of that curve
// widened on every side by `margin` pixels (the bias delivered RPCs carry: 0.5-1.2 px per pair on the
// Pléiades triplet, several pixels on other products) plus the curve's largest distance from its chord.
//
// 1. Coarse: the strongest keypoints of image 1 (GuidedMatchOptions coarse_keypoints over coarse_grid^2
//    cells) are matched in their regions over the whole height range, and an affine F is fitted to
//    those matches by RANSAC; each inlier gives the height at which its curve passes its image-2
//    position. The margin follows the bias the data show: tried at `margin` first, then 4 times wider
//    (up to `max_margin`) while the F finds no geometry or its inliers' offsets across the curves,
//    widened by step 2's band, reach beyond the margin (a delivered model tens of pixels off); the
//    first geometry within its margin is used, else the one of most inliers. Each coarse cell of image 1
//    gets the height range of the inliers in it and its eight neighbours (or of all of them when fewer
//    than min_cell_samples), widened by parallax_margin pixels converted to metres along the curves.
//    Their offsets across the curves measure the models' bias (relative between the two images): a
//    plane in x1 (shift and drift) is fitted to them.
// 2. Every keypoint is matched in the region of its cell's height range (match_in_regions), moved
//    across by the bias plane and as wide as the affine guided search's band (or 3 x the RMS the plane
//    leaves, if wider) plus the curve's bend, not lengthened beyond the cell's heights. When step 1
//    finds no geometry (fewer than min_inliers), the whole range is used with the widest margin it
//    tried: the search still holds, because it does not depend on the images' content (repetitive
//    texture, small overlaps).
// Pixels: tpkit's convention in both images (x = column, y = row, (0, 0) the centre of the top-left
// pixel); the models use the same convention (rpc_io.hpp converts DIMAP's where it is read).
#pragma once
#include <opencv2/core/types.hpp>
#include <vector>

#include "tpkit/match/affine_fundamental.hpp"
#include "tpkit/match/guided_matching.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

struct RpcGuideOptions {
  // Heights searched, metres above the ellipsoid, when height_given; else the range both models are
  // valid for (height offset -/+ scale of each, intersected).
  bool height_given = false;
  double h_lo = 0, h_hi = 0;
  double margin = 10;       // pixels around the chord of the epipolar curve (step 1's first try)
  double max_margin = 160;  // step 1 widens its margin 4-fold up to this while the bias needs it
  int samples = 5;     // heights along a curve (>= 2) that bound its distance from the chord
};

struct RpcGuidedStats {
  double h_lo = 0, h_hi = 0;              // the heights searched (step 1)
  double coarse_margin = 0;               // step 1's margin whose geometry was used (or the widest tried)
  long coarse_putative = 0, coarse_inliers = 0;
  bool narrowed = false;                  // step 2 used per-cell height ranges
  double cell_h_lo = 0, cell_h_hi = 0;    // their extremes, metres
  double bias_min = 0, bias_max = 0;      // the inliers' offsets across their curves, pixels
  double bias_rms = 0;                    // RMS of the offsets from the bias plane, pixels
  long unlocalized = 0;                   // keypoints without a curve (the model of image 1 failed)
  double mean_length = 0;                 // mean chord length of step 2's regions, pixels of image 2
  double max_bend = 0;                    // largest distance of a curve from its chord, pixels
  double candidates_per_query = 0;
};

// The height range of options `r` for models a and b; InputError when the models' validity ranges do
// not meet (and no range was given), UsageError when the range given is empty.
void rpc_height_range(const RpcModel& a, const RpcModel& b, const RpcGuideOptions& r, double& h_lo, double& h_hi);

// The region in image 2 of each of the image-1 pixels kp1 over the heights [h_lo[i], h_hi[i]]: the
// chord of its curve (`samples` heights) lengthened by `along` pixels at both ends and widened by
// `across` pixels plus the curve's bend on both sides; length -1 where the curve could not be computed.
std::vector<SearchRegion> rpc_search_regions(const RpcModel& a, const RpcModel& b, const std::vector<cv::KeyPoint>& kp1,
                                             const std::vector<double>& h_lo, const std::vector<double>& h_hi,
                                             double along, double across, int samples, int threads,
                                             RpcGuidedStats* stats = nullptr);

// Steps 1 and 2. w1 x h1: image 1's size; `ransac`: step 1's F fit. Matches: rows of K1.desc / K2.desc,
// sorted by i1. Deterministic for any thread count.
std::vector<DescriptorMatch> rpc_guided_match(const Keypoints& K1, const Keypoints& K2, long w1, long h1, const RpcModel& a,
                                              const RpcModel& b, const DescriptorMatchOptions& desc,
                                              const GuidedMatchOptions& g, const RpcGuideOptions& r,
                                              const AffineFundamentalRansac& ransac, int min_inliers, int threads,
                                              RpcGuidedStats* stats = nullptr);

}  // namespace tpkit
