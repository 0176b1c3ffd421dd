#include "tpkit/match/root_sift.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tpkit {

namespace {
// The L1 norm in four partial sums, exact in any order for the rows the detector gives (integers 0..255,
// at most 2^15 in all); then the components, a loop the compiler vectorises: this file is compiled
// without errno for the square root (lib/CMakeLists.txt), whose argument is never negative here. One
// component a step, scalar divisions and square roots, took 3.3% of a 10000² image's detection, on one thread.
template <typename T>
void root_row(const T* in, uint8_t* out, int n) {
  double part[4] = {0, 0, 0, 0};
  int k = 0;
  for (; k + 4 <= n; k += 4)
    for (int j = 0; j < 4; ++j) part[j] += static_cast<double>(in[k + j]);
  for (; k < n; ++k) part[0] += static_cast<double>(in[k]);
  const double l1 = (part[0] + part[1]) + (part[2] + part[3]);
  if (!(l1 > 0)) {
    std::fill(out, out + n, uint8_t{0});
    return;
  }
  // round half up by truncation of x + 0.5 (x >= 0: std::round's value)
  for (k = 0; k < n; ++k) {
    const double x = static_cast<double>(in[k]);  // (x + |x|) / 2: max(x, 0) without a branch (x is not NaN: l1 is)
    const int q = static_cast<int>(512.0 * std::sqrt(0.5 * (x + std::fabs(x)) / l1) + 0.5);
    out[k] = static_cast<uint8_t>(q < 255 ? q : 255);
  }
}

void check_sift(const cv::Mat& sift) {
  if (sift.channels() != 1 || (sift.depth() != CV_32F && sift.depth() != CV_8U))
    throw std::invalid_argument("root_sift: descriptors must be one-channel CV_32F or CV_8U rows");
}
}  // namespace

void root_sift_row(const cv::Mat& sift, int row, uint8_t* out) {
  check_sift(sift);
  if (sift.depth() == CV_32F)
    root_row(sift.ptr<float>(row), out, sift.cols);
  else
    root_row(sift.ptr<uint8_t>(row), out, sift.cols);
}

cv::Mat root_sift(const cv::Mat& sift) {
  if (sift.empty()) return cv::Mat(0, sift.cols > 0 ? sift.cols : 128, CV_8U);
  check_sift(sift);
  cv::Mat out(sift.rows, sift.cols, CV_8U);
  for (int r = 0; r < sift.rows; ++r) root_sift_row(sift, r, out.ptr<uint8_t>(r));
  return out;
}

}  // namespace tpkit
