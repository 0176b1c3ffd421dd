// OpenCV's own thread pool under tpkit's parallelism.
//
// tpkit runs OpenCV from several of its own threads at once (tiles of one image, images, pairs: see
// parallel_for.hpp), and OpenCV parallelises inside each call on its pool (TBB in Debian's build).
// cv::setNumThreads re-creates that pool; doing so while another thread is inside it hangs or crashes
// (seen: tp-match's every-pair mode spinning for ever in BFMatcher::knnMatch). So the pool is sized
// once per process, before the first OpenCV call, and never again: the tools call
// set_opencv_threads(--threads) at start-up, and no library function touches the setting.
#pragma once
#include "tpkit/core/parallel_for.hpp"  // kMaxThreads

namespace tpkit {

// Sizes OpenCV's pool for the whole process (threads >= 1, at most kMaxThreads), to the processors at
// most: TBB's pool is already made for them, and a bigger one asked of it prints an unprefixed "TBB
// Warning: The number of workers is currently limited to N" (tp-match --threads 8 on two cores). The
// first call wins; later calls do nothing and return false, as does a call with a count out of range.
bool set_opencv_threads(int threads);

}  // namespace tpkit
