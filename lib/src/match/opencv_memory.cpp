#include "tpkit/match/opencv_memory.hpp"

#include <sys/mman.h>

#include <cstdlib>
#include <mutex>
#include <opencv2/core.hpp>

namespace tpkit {

namespace {
constexpr size_t kLargePage = size_t(2) << 20;

// OpenCV's standard allocator (modules/core/src/matrix.cpp, StdMatAllocator) with large blocks taken
// 2 MiB-aligned and advised for huge pages.
class LargePageMatAllocator : public cv::MatAllocator {
 public:
  cv::UMatData* allocate(int dims, const int* sizes, int type, void* data0, size_t* step, cv::AccessFlag,
                         cv::UMatUsageFlags) const override {
    size_t total = CV_ELEM_SIZE(type);
    for (int i = dims - 1; i >= 0; i--) {
      if (step) {
        if (data0 && step[i] != cv::Mat::AUTO_STEP) {
          CV_Assert(total <= step[i]);
          total = step[i];
        } else {
          step[i] = total;
        }
      }
      total *= static_cast<size_t>(sizes[i]);
    }
    auto* u = new cv::UMatData(this);
    u->data = u->origdata = data0 ? static_cast<uchar*>(data0) : allocate_bytes(total);
    u->size = total;
    if (data0) u->flags |= cv::UMatData::USER_ALLOCATED;
    return u;
  }
  bool allocate(cv::UMatData* u, cv::AccessFlag, cv::UMatUsageFlags) const override { return u != nullptr; }
  void deallocate(cv::UMatData* u) const override {
    if (!u) return;
    CV_Assert(u->urefcount == 0);
    CV_Assert(u->refcount == 0);
    if (!(u->flags & cv::UMatData::USER_ALLOCATED)) {
      if (u->size >= kLargePage) std::free(u->origdata);
      else cv::fastFree(u->origdata);
      u->origdata = nullptr;
    }
    delete u;
  }

 private:
  static uchar* allocate_bytes(size_t n) {
    if (n < kLargePage) return static_cast<uchar*>(cv::fastMalloc(n));
    const size_t rounded = (n + kLargePage - 1) / kLargePage * kLargePage;
    void* p = std::aligned_alloc(kLargePage, rounded);
    if (!p) CV_Error(cv::Error::StsNoMem, "out of memory");
    ::madvise(p, rounded, MADV_HUGEPAGE);  // advice only: without huge pages the block is ordinary memory
    return static_cast<uchar*>(p);
  }
};
}  // namespace

void use_large_page_mat_allocator() {
  static std::once_flag once;
  std::call_once(once, [] {
    static LargePageMatAllocator allocator;
    cv::Mat::setDefaultAllocator(&allocator);
  });
}

}  // namespace tpkit
