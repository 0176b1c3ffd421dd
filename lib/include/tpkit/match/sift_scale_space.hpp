// SIFT keypoints and descriptors of one 8-bit image (Lowe 2004): tpkit's own scale space.
//
// The method and its parameters are Lowe's as OpenCV 4 implements them (the image upsampled twice into
// the first octave, `octave_layers` layers an octave, extrema of the difference of Gaussians with
// OpenCV's contrastThreshold and edgeThreshold, 36-bin orientation histograms, 4 x 4 x 8 descriptors
// clamped at 0.2 and scaled to 512), so that SiftOptions keep their meaning; the computation is
// organised for speed and memory:
//   - one octave at a time, and the differences of Gaussians taken where they are read, never stored:
//     the scale space holds one octave's Gaussian layers at most (OpenCV holds every octave's layers
//     and differences at once): for a 1024-pixel tile with its 96-pixel overlaps (1216², upsampled
//     2432²) 142 MB at the peak, not 346;
//   - the Gaussian blurs tpkit's own (gaussian_blur.hpp: OpenCV's kernel and borders, up to twice as
//     fast) in horizontal strips on OpenCV's thread pool (OpenCV blurs a float image on one thread);
//   - in a detection tile, extrema, orientations and descriptors for the tile's core only
//     (ScaleSpaceOptions::region): its overlap serves the blurs;
//   - gradient magnitude and orientation computed once per pixel of a layer and shared by every
//     orientation histogram and descriptor that samples it (OpenCV computes them, and the Gaussian
//     weight's exponential, afresh for every sample of every window: an upsampled-octave descriptor
//     samples 1200-4800 pixels, and neighbouring windows overlap);
//   - the Gaussian weights of a window from two one-dimensional tables (the weight is separable in
//     the unrotated offsets), and each row of a descriptor window visited only over the columns whose
//     rotated position falls in the 4 x 4 cells;
//   - descriptor windows sampled at every second pixel of their octave, in rows and columns (in the
//     upsampled octave, the input's own pixels): a quarter of the samples, the same information (a
//     window is at least 24 octave pixels wide, its gradient maps blurred by sigma >= 2 of them).
// Differences from OpenCV, all small: positions use the half-pixel convention of the upsampling
// (OpenCV's upsampled-octave positions are 0.25 px right of and below the pixel they describe, in every
// octave); descriptor windows are centred on the keypoint's sub-pixel position rather than on its
// nearest pixel. Keypoints are the same fields as OpenCV's (size = 2 x the scale in pixels, angle in
// degrees as OpenCV measures it, response = |D| at the extremum, octave packed as OpenCV packs it), so
// that matching (keypoint_affine) reads them alike.
//
// Pixels: x = column, y = row, (0, 0) the centre of the top-left pixel of `image`. The result does not
// depend on the thread count of OpenCV's pool.
#pragma once
#include <limits>
#include <opencv2/core.hpp>
#include <vector>

namespace tpkit {

struct ScaleSpaceOptions {
  int octave_layers = 3;
  double contrast = 0.04;  // |D| at the extremum x octave_layers, D on grey levels / 255 (OpenCV contrastThreshold)
  double edge = 10;        // largest ratio of principal curvatures kept (OpenCV edgeThreshold)
  double sigma = 1.6;      // blur of the first layer of each octave, in that octave's pixels
  // Where keypoints are wanted, in the image's pixels: x0 <= x < x1 and y0 <= y < y1 (by default
  // everywhere). The blurs cover the whole image; extrema are sought over the region and 7 octave
  // pixels around it (an extremum's sub-pixel steps move it 6 of them at most), and only the keypoints
  // inside are oriented and described: the same keypoints and descriptors as the whole image's there.
  // A detection tile (sift_tiles.hpp) wants its core: its overlap is there for the blurs only.
  struct Region {
    double x0 = -std::numeric_limits<double>::infinity(), y0 = -std::numeric_limits<double>::infinity();
    double x1 = std::numeric_limits<double>::infinity(), y1 = std::numeric_limits<double>::infinity();
    bool contains(double x, double y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
  } region;
};

// Keypoints of `image` (CV_8U, one channel) where `mask` (empty, or CV_8U of the image's size) is
// non-zero at the keypoint's nearest pixel, and their SIFT descriptors (n x 128, CV_32F, values 0..255
// as OpenCV's). Duplicates (same position, size and angle) are removed.
void detect_sift_scale_space(const cv::Mat& image, const cv::Mat& mask, const ScaleSpaceOptions& o,
                             std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors);

// Keeps in `idx` (indices into kp, increasing) the n with the strongest response (of equal ones, the
// earlier), still increasing; n <= 0 keeps all.
void keep_strongest(const std::vector<cv::KeyPoint>& kp, std::vector<int>& idx, int n);

}  // namespace tpkit
