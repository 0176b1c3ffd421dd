#include "tpkit/match/root_sift.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tpkit {

namespace {
template <typename T>
void root_row(const T* in, uint8_t* out, int n) {
  double l1 = 0;
  for (int k = 0; k < n; ++k) l1 += static_cast<double>(in[k]);
  if (!(l1 > 0)) {
    std::fill(out, out + n, uint8_t{0});
    return;
  }
  // round half up by truncation of x + 0.5 (x >= 0: std::round's value), a loop the compiler vectorises
  for (int k = 0; k < n; ++k) {
    const double v = std::max(0.0, static_cast<double>(in[k])) / l1;
    out[k] = static_cast<uint8_t>(std::min(255.0, static_cast<double>(static_cast<int>(512.0 * std::sqrt(v) + 0.5))));
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
