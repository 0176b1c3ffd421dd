// tp-match's pipeline for one pair of images (image 1 -> image 2): SIFT by tiles (sift_tiles.hpp),
// ratio + mutual nearest neighbours (match_descriptors.hpp), affine fundamental matrix RANSAC
// (affine_fundamental.hpp), optional grid thinning, then least-squares matching of each verified
// match (lsm_refine.hpp) region by region. Image 1's position of every record is its keypoint
// position (the LSM template is fixed there); image 2's is refined.
//
// Records: id1 x1 y1 id2 x2 y2 kx2 ky2 [sigma corr] -- (kx2, ky2) is image 2's keypoint position,
// sigma the LSM standard deviation of (x2, y2) in pixels, corr the final correlation.
#pragma once
#include <cstdint>
#include <string>

#include "tpkit/formats.hpp"
#include "tpkit/image_tiles.hpp"
#include "tpkit/lsm_refine.hpp"
#include "tpkit/match_descriptors.hpp"
#include "tpkit/sift_tiles.hpp"

namespace tpkit {

struct PairMatchOptions {
  SiftOptions sift;
  DescriptorMatchOptions desc;
  double ransac_threshold = 1.0;  // pixels (geometric distance to the affine F, R^4)
  int ransac_iterations = 20000;
  uint64_t seed = 1;
  int min_inliers = 12;           // fewer verified matches: the images are taken not to overlap
  int grid = 0;                   // grid cells per side (0 = off)
  int per_cell = 4;               // matches kept per grid cell (best ratio first)
  bool refine = true;
  LsmOptions lsm;
  long refine_tile = 256;         // image-1 region refined at a time (bounded memory, one per thread)
  int threads = 1;
  bool progress = false;
};

struct PairMatchStats {
  long keypoints1 = 0, keypoints2 = 0, putative = 0, verified = 0, gridded = 0, refined = 0;
  double ransac_rms = 0;
  double seconds[4] = {0, 0, 0, 0};             // wall time of detection, matching, verification, refinement
  long dropped[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // by LsmStatus
  bool overlap = true;                         // false: too few verified matches, zero records
};

Matches match_pair(const ImageSource& a, const ImageSource& b, const PairMatchOptions& o, PairMatchStats* stats = nullptr);

// Initial local map image 1 -> image 2 from two SIFT keypoints: (size2 / size1) R(angle2 - angle1),
// angles in OpenCV's convention (degrees, from +x towards +y in pixel coordinates).
Eigen::Matrix2d keypoint_affine(double size1, double angle1_deg, double size2, double angle2_deg);

}  // namespace tpkit
