// Putative correspondences between two descriptor sets (image 1 -> image 2): nearest neighbour with
// Lowe's ratio test and a mutual (cross) check, exact search for small sets and FLANN kd-trees
// (approximate, seeded, deterministic) for large ones; and a grid filter that spreads matches evenly.
#pragma once
#include <opencv2/core.hpp>
#include <vector>

namespace tpkit {

struct DescriptorMatchOptions {
  double ratio = 0.8;        // keep when d(best) < ratio * d(second best), distances in descriptor units
  bool mutual = true;        // keep only pairs that are each other's nearest neighbour
  long exact_below = 4000;   // exact (brute force) search when both sets are smaller than this
  int flann_trees = 4;
  int flann_checks = 64;     // leaves visited per query by the approximate search
};

struct DescriptorMatch {
  int i1, i2;      // rows of desc1, desc2
  float distance;  // L2 distance of the descriptors
  float ratio;     // distance / second-best distance (0..1)
};

// desc1, desc2: CV_32F or CV_8U rows (converted to float). Result sorted by i1. Deterministic for the same input.
std::vector<DescriptorMatch> match_descriptors(const cv::Mat& desc1, const cv::Mat& desc2, const DescriptorMatchOptions& o);

// Keeps at most `per_cell` matches (lowest `score` first) in each cell of a cells x cells grid over a
// width x height image (positions x = column, y = row). Returns kept indices, ascending.
std::vector<size_t> grid_select(const std::vector<cv::Point2f>& pts, const std::vector<float>& score, long width, long height,
                                int cells, int per_cell);

}  // namespace tpkit
