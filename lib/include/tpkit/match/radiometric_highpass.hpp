// Images of different dates or conditions: the least-squares matching (lsm_refine.hpp) models the
// radiometry of a window by one gain and one offset, but another sun's shading of the relief, a
// non-linear tone curve or a seasonal field change the radiometry *within* the window, and the fit then
// moves the position to explain them. Subtracting each image's local mean (a Gaussian of sigma pixels,
// i.e. a high-pass) before refinement keeps the texture and drops what varies slowly. On a pair of one
// date it only adds noise, so it is chosen per pair from the matches themselves: each candidate refines a
// sample of the verified matches, and the one whose refined positions lie closest to their own epipolar
// geometry wins (the spread across the epipolar lines is the part of the position error a pair can see;
// along them it is parallax). tp-synth 1024² pairs, median error of the correct matches against the
// truth unfiltered -> at sigma 1 px, and the spreads the choice sees: same date 0.052 -> 0.063 px (spread
// 0.023 -> 0.027); second date 0.114 -> 0.073 (0.065 -> 0.042); second date + clouds + blur 1.5 0.232
// -> 0.114 (0.160 -> 0.095; 2 px, chosen, 0.100); blur 1.5 alone 0.105 -> 0.130 (0.043 -> 0.059).
//
// Conventions: sigma in pixels of each image; 0 filters nothing. Spreads in pixels of image 2.
#pragma once
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "tpkit/core/image_io.hpp"

namespace tpkit {

// r - G_sigma * r, the Gaussian by normalized convolution (blur_raster): nodata pixels (NaN) stay NaN and
// do not leak into their neighbours' local mean. sigma <= 0 leaves r unchanged.
void highpass_raster(Raster& r, double sigma);

// The spread of matches (rows x1 y1 x2 y2) about their own affine epipolar geometry: the affine
// fundamental matrix fitted by least squares to all of them, refitted once without those beyond 5
// median absolute residuals, then the median distance of all to their epipolar lines in image 2
// (pixels). NaN with fewer than 8 rows or no epipolar direction.
double epipolar_spread(const Eigen::MatrixX4d& xy);

struct HighpassChoice {
  double sigma = 0;          // the chosen local-mean sigma (pixels), 0 = none
  double spread = 0;         // its epipolar spread over the sample
  double spread_none = 0;    // the spread without the high-pass
  std::vector<double> tried; // candidates evaluated besides 0, in order, and their spreads
  std::vector<double> tried_spread;
  // where a candidate is compared with the best before it over the views both accepted
  // (choose_track_highpass): that one's spread over them, and how many (empty otherwise), and the
  // relative gain a candidate needed
  std::vector<double> tried_reference;
  std::vector<long> tried_common;
  double paired_gain = 0;
  long samples = 0;          // matches in the sample (set by the caller)
};

// Evaluates spread(0), then the candidates in order (increasing sigma) while each improves on the best
// so far, the first by more than min_gain (relative), the others by more than next_gain: the last that did
// is chosen, 0 when none did. A NaN spread stops the search. A same-date pair so costs two evaluations.
HighpassChoice choose_highpass(const std::function<double(double)>& spread, const std::vector<double>& candidates = {1.0, 2.0},
                               double min_gain = 0.1, double next_gain = 0);

// A "# highpass:" header value: the filter as applied to `images` ("both images", "every image"), then
// "(--highpass)" when given, `not_estimated` when no sample was measured, else "(estimated on N <sampled>:
// <measure> S0 px unfiltered, S1 px at 1 px, ...)".
std::string describe_highpass_choice(const HighpassChoice& h, const std::string& images, bool given, const std::string& sampled,
                                     const std::string& measure, const std::string& not_estimated);

}  // namespace tpkit
