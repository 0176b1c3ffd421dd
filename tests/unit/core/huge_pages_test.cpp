// advise_huge_pages (huge_pages.hpp): the whole 2 MiB pages inside the range, and nothing around them,
// are advised for huge pages (VmFlags "hg" in /proc/self/smaps); the memory is unchanged.
#include "tpkit/core/huge_pages.hpp"

#include <gtest/gtest.h>
#include <sys/mman.h>

#include <cstdint>
#include <cstring>

#include "../support/process_maps.hpp"

using namespace tpkit;

using tpkit_test::advised_huge;
using tpkit_test::vm_flags;

TEST(HugePages, OnlyTheWhole2MiBPagesInsideTheRangeAreAdvised) {
  const size_t H = kHugePage;
  // 8 MiB, its start on a huge page
  void* m = ::mmap(nullptr, 9 * H, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  ASSERT_NE(m, MAP_FAILED);
  char* base = reinterpret_cast<char*>((reinterpret_cast<uintptr_t>(m) + H - 1) & ~(uintptr_t(H) - 1));
  std::memset(base, 5, 8 * H);
  // from 1 MiB to 7 MiB: the pages [2, 6) MiB are whole inside it
  advise_huge_pages(base + H / 2, 3 * H);
  EXPECT_FALSE(advised_huge(base + H - 1)) << vm_flags(base + H - 1);
  EXPECT_TRUE(advised_huge(base + H)) << vm_flags(base + H);
  EXPECT_TRUE(advised_huge(base + 3 * H - 1));
  EXPECT_FALSE(advised_huge(base + 3 * H)) << vm_flags(base + 3 * H);
  for (size_t k = 0; k < 8 * H; k += 4096) ASSERT_EQ(base[k], 5);
  // a range holding no whole 2 MiB page: nothing
  advise_huge_pages(base + 5 * H + 1, H);
  EXPECT_FALSE(advised_huge(base + 5 * H + H / 2));
  ::munmap(m, 9 * H);
}
