// What a region run of tp-match (match_region.hpp) needs to know of the whole pair, found cheaply:
// the detector's 8-bit stretch of each whole image (so that a tile's keypoints and ids are exactly a
// whole run's), and a coarse map image 1 -> image 2 that says where the keypoints of an image-1 window
// can fall in image 2.
//
// Coarse stage: each image is read strip by strip and averaged in f x f blocks (f the smallest factor
// that brings its larger side to at most `max_side` pixels; a block with an invalid pixel is invalid),
// rendered with its stretch, its strongest SIFT keypoints (max_keypoints) matched over all descriptors (ratio test, mutual check),
// and an affine fundamental matrix fitted by RANSAC. The 2-D affine map x2 = A [x1; 1] is then the
// least-squares fit to the F inliers, and `spread` the largest distance of an inlier from it (the
// parallax range the map leaves, plus the coarse stage's error), both in full-resolution pixels.
// Decimated pixel i holds full pixels [f i, f i + f): its centre is the full-resolution x = f i + (f - 1) / 2.
// Memory: the two decimated images and one strip; time: one pass over each image.
//
// The file (kind geometry, man/tpkit-formats.5): image1/image2 lines, detector1/detector2 metadata
// (detector_tag), and one record a11 a12 a13 a21 a22 a23 spread lo1 hi1 lo2 hi2 (A row-major; the
// stretch of image k is lok..hik).
#pragma once
#include <Eigen/Core>
#include <array>
#include <string>

#include "tpkit/core/formats.hpp"
#include "tpkit/match/sift_tiles.hpp"

namespace tpkit {

struct PairGeometryOptions {
  long max_side = 1024;         // decimated images' larger side, pixels
  int max_keypoints = 4000;     // strongest SIFT keypoints of each decimated image
  double ransac_threshold = 1.0;  // affine F RANSAC on the decimated pixels
  int min_inliers = 12;
  uint64_t seed = 1;
};

struct PairGeometry {
  ImageRef image1, image2;
  std::string detector1, detector2;  // detector_tag of each image
  Stretch stretch1, stretch2;        // percentile_stretch of each whole image
  Eigen::Matrix<double, 2, 3> A = Eigen::Matrix<double, 2, 3>::Zero();  // x2 = A [x1; y1; 1], pixels
  double spread = 0;                 // pixels in image 2
  long coarse_matches = 0, inliers = 0;
  long scale1 = 1, scale2 = 1;       // decimation factors
};

// Throws InputError (exit 1) when the images share no coarse geometry (too few inliers).
PairGeometry estimate_pair_geometry(const ImageSource& a, const ImageSource& b, const SiftOptions& sift,
                                    const PairGeometryOptions& g);

void save_pair_geometry(const std::string& path, const PairGeometry& G);
PairGeometry read_pair_geometry(const std::string& path);
// Throws InputError naming `path` when G was made for other images (its image1/image2 paths name other
// files than a and b, or sizes differ) or detector options.
void check_pair_geometry(const PairGeometry& G, const std::string& path, const ImageSource& a, const ImageSource& b,
                         const SiftOptions& sift);

// Bounding box [x0, x1) x [y0, y1) in image 2 of where the image-1 window [x0, x1) x [y0, y1) can
// fall: A of its corners, grown by spread + margin pixels (pixel-centre coordinates, not clipped).
std::array<double, 4> image2_window(const PairGeometry& G, const std::array<double, 4>& window1, double margin);

}  // namespace tpkit
