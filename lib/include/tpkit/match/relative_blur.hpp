// Images of different sharpness: one a coarser sensor resampled, a hazy or defocused date. The
// least-squares matching (lsm_refine.hpp) models geometry (affine, quadratic) and radiometry (gain and
// offset) but not a difference of point spread functions: between a sharp and a blurred window its fit
// is poor (low correlation, large sigma) and its positions scatter. Blurring the sharper image's windows
// by the relative blur before refinement makes the two windows alike again.
//
// Convention: the relative blur is a signed Gaussian standard deviation in pixels; sigma > 0 blurs image
// 1 (image 2 is the blurrier), sigma < 0 blurs image 2 by |sigma|, 0 blurs nothing.
// It is estimated per pair from the matches themselves: the final correlation of the least-squares
// matching peaks where the two windows' PSFs agree (a synthetic pair whose view 2 has a Gaussian PSF of
// 1.5 px: median correlation 0.945 unblurred, 0.990 at 1.0, 0.995 at 1.5, 0.972 at 2.0).
#pragma once
#include <functional>

#include "tpkit/core/image_io.hpp"

namespace tpkit {

// Gaussian blur of standard deviation sigma (pixels, > 0) by normalized convolution: nodata pixels (NaN)
// neither spread nor darken their neighbours, and stay NaN. Borders: only the raster's own pixels.
void blur_raster(Raster& r, double sigma);

struct RelativeBlur {
  double sigma = 0;      // the chosen relative blur (signed, see above)
  double score = 0;      // its median correlation over the sample
  double score_none = 0; // the median correlation without blur
  int evaluations = 0;   // sample refinements run
};

// Searches the signed blur in [-max_sigma, max_sigma] that maximises score(sigma) (the sample's median
// final LSM correlation): from 0 in steps of `step` towards the side that improves while it improves,
// then half a step either side of the best. A blur is chosen only when it raises the score by more than
// `min_gain` over no blur (same-sensor pairs keep 0).
RelativeBlur estimate_relative_blur(const std::function<double(double)>& score, double max_sigma = 3, double step = 0.5,
                                    double min_gain = 0.005);

}  // namespace tpkit
