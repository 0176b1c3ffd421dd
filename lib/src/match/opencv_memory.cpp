#include "tpkit/match/opencv_memory.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <cstdlib>
#include <map>
#include <mutex>
#include <opencv2/core.hpp>
#include <unordered_map>

#include "tpkit/core/huge_pages.hpp"

namespace tpkit {

namespace {
// At most this much freed memory is kept for reuse; more goes back to the system at once.
constexpr size_t kMaxPooled = size_t(1) << 30;

constexpr size_t kPage = size_t(4) << 10;

size_t round_up(size_t n, size_t unit) { return (n + unit - 1) / unit * unit; }

// Rounded up to whole 2 MiB pages where that wastes at most a quarter of the block: a pyramid level
// (23.7 MB for a 1024 tile with its overlap, 24 MiB mapped; 14.8 MB for a 768 tile, 16 MiB) but not a
// tile's descriptors (about 2.5 MB, which 4 MiB would hold at 60% waste: on a 10000² pair, 200 tiles of
// them held about 150 MiB of nothing at the end of detection); those are rounded to 4 KiB pages, and only
// their whole 2 MiB pages are huge (map_block). The 768 tile's planes were in 4 KiB pages
// under an earlier limit of an eighth; on a virtual machine whose page faults cost much, a detection job
// of nine 768 tiles (tp-plan's) then took 2.0 s, and 1.8 s on huge pages.
bool on_huge_pages(size_t n) { return round_up(n, kHugePage) - n <= n / 4; }
size_t block_size(size_t n) { return on_huge_pages(n) ? round_up(n, kHugePage) : round_up(n, kPage); }

// A request may take a pooled block up to kShareRatio times its size: a scale space's higher octaves
// (planes a quarter of the first octave's and less) then run in the first octave's freed planes. With
// blocks of about their own size only, the next tile's first octave found the pool full of the higher
// octaves' blocks and evicted them to map its own, every tile: one 10000² image's detection mapped (and
// the kernel zeroed) 777 blocks, 218 once requests from 4 MiB shared (its wall time on 2 threads 18.2 ->
// 17.2 s, the same peak). With 768 tiles the second octave's planes (3.7 MB) were below those 4 MiB: a
// detection job of nine tiles mapped 83 blocks, now 9 (3.5 -> 2.2 s); the whole 10000² pair at 768 tiles
// 117 -> 110 CPU s at the same peak (953-1060 MiB over runs of both). At 1024 tiles, where a tile's
// descriptors (2.5 MB, which live until the image is gathered) may now hold a freed octave plane, the
// pair's peak did not move.
constexpr size_t kShareRatio = 5;

// Large blocks: mapped 2 MiB-aligned and advised for huge pages (or, where that rounding would waste more
// than a quarter of the block, in whole 4 KiB pages), and on free kept for the next request that fits
// them (see kShareRatio) instead of unmapped. Blocks in use and in the pool together
// never exceed the most ever in use at once (pooled blocks are unmapped to make room), so the pool adds
// nothing to the peak; it holds at most kMaxPooled bytes and is emptied by release_large_blocks(). Blocks are mapped and
// unmapped directly rather than taken from malloc: from malloc's heaps, memory backed by huge pages
// stayed resident after free (a 10000² pair peaked at 2.2 GB that way, against 1.4 GB).
class LargeBlocks {
 public:
  void* take(size_t n) {
    const size_t size = block_size(n);
    {
      std::lock_guard<std::mutex> lock(m_);
      auto it = free_.lower_bound(size);
      if (it != free_.end() && it->first <= kShareRatio * size) {
        void* p = it->second;
        pooled_ -= it->first;
        in_use_ += it->first;
        high_ = std::max(high_, in_use_);
        mapped_[p] = it->first;
        free_.erase(it);
        return p;
      }
      // no block fits: free pooled ones until what is mapped stays within the most ever in use at once,
      // so that the pool adds nothing to the peak (pooled blocks of another size would pile up)
      while (!free_.empty() && in_use_ + pooled_ + size > std::max(high_, in_use_ + size)) {
        auto big = std::prev(free_.end());
        ::munmap(big->second, big->first);
        pooled_ -= big->first;
        free_.erase(big);
      }
    }
    void* p = map_block(size);
    if (!p) return nullptr;
    std::lock_guard<std::mutex> lock(m_);
    mapped_[p] = size;
    in_use_ += size;
    high_ = std::max(high_, in_use_);
    return p;
  }
  void give(void* p) {
    std::lock_guard<std::mutex> lock(m_);
    auto it = mapped_.find(p);
    if (it == mapped_.end()) return;
    const size_t size = it->second;
    mapped_.erase(it);
    in_use_ -= size;
    if (pooled_ + size > kMaxPooled) {
      ::munmap(p, size);
      return;
    }
    free_.emplace(size, p);
    pooled_ += size;
  }
  void release() {
    std::lock_guard<std::mutex> lock(m_);
    for (const auto& [size, p] : free_) ::munmap(p, size);
    free_.clear();
    pooled_ = 0;
  }

 private:
  // `size` bytes of fresh memory, 2 MiB-aligned, its whole 2 MiB pages advised for huge pages: all of a
  // block rounded to them, the head of one that is not (a tile's 2.5 MB of descriptors: one fault for its
  // first 2 MiB, 4 KiB pages for the rest, where all 4 KiB pages took 101 thousand of a 10000² pair's faults)
  static void* map_block(size_t size) {
    const size_t len = size + kHugePage;
    void* p = ::mmap(nullptr, len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) return nullptr;
    // keep the 2 MiB-aligned part, give back the rest
    const uintptr_t start = reinterpret_cast<uintptr_t>(p), aligned = (start + kHugePage - 1) & ~(uintptr_t(kHugePage) - 1);
    const size_t head = aligned - start, tail = len - head - size;
    if (head) ::munmap(p, head);
    if (tail) ::munmap(reinterpret_cast<void*>(aligned + size), tail);
    advise_huge_pages(reinterpret_cast<void*>(aligned), size);  // advice only: without huge pages, ordinary memory
    return reinterpret_cast<void*>(aligned);
  }

  std::mutex m_;
  std::multimap<size_t, void*> free_;        // size -> block, free
  std::unordered_map<void*, size_t> mapped_;  // block in use -> its mapped size
  size_t pooled_ = 0, in_use_ = 0, high_ = 0;  // bytes: free in the pool, handed out, most handed out at once
};

LargeBlocks& large_blocks() {
  static LargeBlocks* blocks = new LargeBlocks;  // never destroyed: matrices may outlive static destruction
  return *blocks;
}

// OpenCV's standard allocator (modules/core/src/matrix.cpp, StdMatAllocator) with blocks of 2 MiB and
// more from LargeBlocks.
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
      if (u->size >= kHugePage) large_blocks().give(u->origdata);
      else cv::fastFree(u->origdata);
      u->origdata = nullptr;
    }
    delete u;
  }

 private:
  static uchar* allocate_bytes(size_t n) {
    if (n < kHugePage) return static_cast<uchar*>(cv::fastMalloc(n));
    void* p = large_blocks().take(n);
    if (!p) CV_Error(cv::Error::StsNoMem, "out of memory");
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

void release_large_blocks() { large_blocks().release(); }

}  // namespace tpkit
