// The pool of large blocks behind OpenCV's matrices (opencv_memory.hpp): a freed block serves the next
// matrix that fits it, of its size or up to five times smaller (a higher octave in a first octave's
// plane, for 1024 and 768 tiles alike); a matrix smaller than that gets a block of its own.
#include "tpkit/match/opencv_memory.hpp"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

using namespace tpkit;

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
