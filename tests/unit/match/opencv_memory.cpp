// The pool of large blocks behind OpenCV's matrices (opencv_memory.hpp): a freed block serves the next
// matrix that fits it, of its size or up to five times smaller (a higher octave in a first octave's
// plane, for 1024 and 768 tiles alike); a matrix smaller than that gets a block of its own.
#include "tpkit/match/opencv_memory.hpp"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <cstdint>

#include "../support/process_maps.hpp"

using namespace tpkit;

using tpkit_test::advised_huge;
using tpkit_test::vm_flags;

TEST(OpencvMemory, FreedPlanesServeTheMatricesThatFitThem) {
  use_large_page_mat_allocator();
  release_large_blocks();
  const uchar* plane_block;
  {
    cv::Mat plane(2432, 2432, CV_32F);  // a first octave's plane of a 1216² tile: 23.7 MB, a 24 MiB block
    plane_block = plane.data;
  }
  {
    cv::Mat again(2432, 2432, CV_32F);
    EXPECT_EQ(again.data, plane_block);
  }
  {
    cv::Mat octave1(1216, 1216, CV_32F);  // the next octave's plane, a quarter of it
    EXPECT_EQ(octave1.data, plane_block);
    cv::Mat second(1216, 1216, CV_32F);  // the block is taken: one of its own
    EXPECT_NE(second.data, plane_block);
  }
  {
    cv::Mat small(1152, 1024, CV_32F);  // 4.5 MiB: 24 MiB is more than five times that
    EXPECT_NE(small.data, plane_block);
  }
  {
    cv::Mat descriptors(20000, 128, CV_8U);  // 2.4 MB: 24 MiB is more than five times that
    EXPECT_NE(descriptors.data, plane_block);
  }
  release_large_blocks();
  // a 768 tile's (960² with its overlap): its second octave's planes, 3.7 MB, run in the first's
  {
    cv::Mat plane(1920, 1920, CV_32F);
    plane_block = plane.data;
  }
  {
    cv::Mat octave1(960, 960, CV_32F);
    EXPECT_EQ(octave1.data, plane_block);
  }
  release_large_blocks();
}

// Every large block starts on a 2 MiB boundary and its whole 2 MiB pages are advised for huge pages:
// all of a plane rounded to them, the first 2 MiB of a tile's 2.5 MB of descriptors and not the rest.
TEST(OpencvMemory, LargeBlocksAreAdvisedForHugePagesByWhole2MiBPages) {
  use_large_page_mat_allocator();
  release_large_blocks();
  const uintptr_t huge = uintptr_t(2) << 20;
  {
    cv::Mat plane(2432, 2432, CV_32F);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(plane.data) % huge, 0u);
    EXPECT_TRUE(advised_huge(plane.data)) << vm_flags(plane.data);
    EXPECT_TRUE(advised_huge(plane.data + plane.total() * plane.elemSize() - 1)) << vm_flags(plane.data);
  }
  release_large_blocks();
  {
    cv::Mat descriptors(20000, 128, CV_8U);  // 2.56 MB: one 2 MiB page and 4 KiB pages
    EXPECT_EQ(reinterpret_cast<uintptr_t>(descriptors.data) % huge, 0u);
    EXPECT_TRUE(advised_huge(descriptors.data)) << vm_flags(descriptors.data);
    EXPECT_TRUE(advised_huge(descriptors.data + huge - 1));
    EXPECT_FALSE(advised_huge(descriptors.data + huge)) << vm_flags(descriptors.data + huge);
    descriptors.setTo(7);
    EXPECT_EQ(descriptors.at<uchar>(19999, 127), 7);
  }
  release_large_blocks();
}
