// OpenCV's large matrices in memory backed by 2 MiB pages.
//
// SIFT builds its scale space from an image upsampled twice: a 1024² tile becomes nine 2048² float
// levels (16 MiB each) plus their differences, allocated afresh for every tile. Each new 4 KiB page costs
// a fault, and on a virtual machine a fault is dear: on Marseille pair 1-2 the kernel's share of
// tp-match's time was 14 % (1.07 s of system time against 3.35 s of user time). Matrices of 2 MiB and more
// are here allocated 2 MiB-aligned and marked MADV_HUGEPAGE, so that the kernel backs them with huge pages
// where transparent huge pages are enabled ("always" or "madvise", Debian's default), 512 times fewer
// faults (a matrix that whole 2 MiB pages would round up by more than a quarter, such as a tile's
// descriptors, is mapped to the next 4 KiB page instead: huge pages for its whole 2 MiB pages, 4 KiB pages
// for the rest); smaller ones, and everything where huge pages are off, are as before. A freed large
// block is kept (up to 1 GiB) for the next matrix that fits it (of its size or up to five times smaller:
// a higher octave in a first octave's plane): the next tile's or image's pyramid then needs neither
// faults nor the kernel's zeroing of fresh pages.
#pragma once

namespace tpkit {

// Makes the allocator above OpenCV's default for the process (cv::Mat::setDefaultAllocator). Call once,
// at start-up, before the first OpenCV call; later calls do nothing.
void use_large_page_mat_allocator();

// Returns the freed large blocks kept for reuse to the system. A pair's matching calls it when it starts
// (the pyramids) and once its descriptors are freed, unless detection goes on beside it.
void release_large_blocks();

}  // namespace tpkit
