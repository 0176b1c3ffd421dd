#include "tpkit/match/opencv_threads.hpp"

#include <algorithm>
#include <mutex>
#include <opencv2/core/utility.hpp>

namespace tpkit {

bool set_opencv_threads(int threads) {
  if (threads < 1 || threads > kMaxThreads) return false;
  static std::once_flag once;
  bool set = false;
  std::call_once(once, [&]() {
    cv::setNumThreads(std::min(threads, cv::getNumberOfCPUs()));
    set = true;
  });
  return set;
}

}  // namespace tpkit
