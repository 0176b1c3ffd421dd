// Transparent huge pages for large buffers.
//
// On a virtual machine a page fault is dear (about 14 µs on the machine the figures of the match
// component were measured on), and a buffer of tens of megabytes written for the first time takes one a
// 4 KiB page. Advised for huge pages before its first touch, it takes one a 2 MiB page instead: where
// transparent huge pages are enabled ("always", or "madvise", Debian's default). Elsewhere the advice
// changes nothing.
#pragma once
#include <cstddef>

namespace tpkit {

constexpr size_t kHugePage = size_t(2) << 20;

// Advises the whole 2 MiB pages inside [p, p + n) for huge pages (madvise MADV_HUGEPAGE). Advice only:
// no error, and memory contents and addresses do not change.
void advise_huge_pages(void* p, size_t n);

}  // namespace tpkit
