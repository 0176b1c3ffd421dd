#include "tpkit/core/huge_pages.hpp"

#include <sys/mman.h>

#include <cstdint>

namespace tpkit {

void advise_huge_pages(void* p, size_t n) {
#ifdef MADV_HUGEPAGE
  const uintptr_t begin = reinterpret_cast<uintptr_t>(p), end = begin + n;
  const uintptr_t first = (begin + kHugePage - 1) & ~(uintptr_t(kHugePage) - 1), last = end & ~(uintptr_t(kHugePage) - 1);
  if (last > first) ::madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
  (void)p, (void)n;
#endif
}

}  // namespace tpkit
