#include "tpkit/match/opencv_memory.hpp"

#include <sys/mman.h>

#include <cstdint>
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
      if (u->size >= kLargePage) ::munmap(u->origdata, round_up(u->size));
      else cv::fastFree(u->origdata);
      u->origdata = nullptr;
    }
    delete u;
  }

 private:
  static size_t round_up(size_t n) { return (n + kLargePage - 1) / kLargePage * kLargePage; }
  // Large blocks are mapped and unmapped directly, so that a freed pyramid goes back to the system at
  // once: from malloc's heaps, memory backed by huge pages stays resident after free (a 10000² pair
  // peaked at 2.2 GB that way, against 1.4 GB).
  static uchar* allocate_bytes(size_t n) {
    if (n < kLargePage) return static_cast<uchar*>(cv::fastMalloc(n));
    const size_t size = round_up(n), len = size + kLargePage;
    void* p = ::mmap(nullptr, len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) CV_Error(cv::Error::StsNoMem, "out of memory");
    // keep the 2 MiB-aligned part, give back the rest
    const uintptr_t start = reinterpret_cast<uintptr_t>(p), aligned = (start + kLargePage - 1) & ~(uintptr_t(kLargePage) - 1);
    const size_t head = aligned - start, tail = len - head - size;
    if (head) ::munmap(p, head);
    if (tail) ::munmap(reinterpret_cast<void*>(aligned + size), tail);
    ::madvise(reinterpret_cast<void*>(aligned), size, MADV_HUGEPAGE);  // advice only: without huge pages, ordinary memory
    return reinterpret_cast<uchar*>(aligned);
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
