// The Gaussian blur of a float plane, for the SIFT scale space (sift_scale_space.hpp).
//
// What cv::GaussianBlur computes for a CV_32F plane (OpenCV's kernel for floats, 2 round(4 sigma) + 1
// taps from getGaussianKernel, reflect-101 borders), organised for speed: the column pass first, into a
// row buffer that holds the borders, then the row pass from it; both use the kernel's symmetry (one
// product per pair of taps) and sum four vectors of output pixels at a time over the taps. OpenCV's row
// pass chains one fused multiply-add per tap on a single accumulator, so that its speed is the adder's
// latency: on the 2432² planes of a detection tile, blurs of 11 to 27 taps take 7-13 ms here against
// OpenCV's 10-27 ms (one thread; 8-21 ms for the baseline x86-64 code). The values differ from OpenCV's
// by rounding only (the sums in another order: 1e-4 grey levels at most on 0..255).
//
// The result depends on the plane and sigma alone: not on the strips it is computed in (horizontal
// strips on OpenCV's thread pool), the threads, or the CPU (cpu_dispatch.hpp: the AVX2 and baseline
// versions do the same operations in each lane).
#pragma once
#include <opencv2/core.hpp>

namespace tpkit {

// `src` blurred by `sigma` (pixels, > 0); src is CV_32F with one channel. `baseline` asks for the
// baseline code where the CPU has AVX2 (tests compare the two).
cv::Mat gaussian_blur(const cv::Mat& src, double sigma, bool baseline = false);
// The same blur at the pixels of `roi` only (clipped to the plane), the values the whole plane's blur has
// there; the plane returned has src's size, its other pixels undefined. For a scale space's layers that
// only the extremum search reads, near the region wanted.
cv::Mat gaussian_blur(const cv::Mat& src, double sigma, const cv::Rect& roi, bool baseline = false);
// The kernel's radius: round(4 sigma) taps on each side of the centre (pixels).
int gaussian_blur_radius(double sigma);

}  // namespace tpkit
