// Pairwise matches files joined into multi-view tracks (tp-chain).
//
// Nodes are (image, keypoint id); every record of every file links its two nodes (union-find).
// Keypoints of one image at the same position (within `same_position` px; SIFT emits one keypoint per
// dominant orientation) are merged into one node first. A track is a connected component:
//  - images follow `images` (default: order of first appearance in the files); the reference is the
//    first of them that the track holds;
//  - a track that holds two different keypoints (positions) of the reference image is dropped; one
//    that holds two different keypoints of another image loses that view (counted as a conflict);
//  - view positions refer to the reference keypoint: the reference view is its keypoint position; a
//    view linked to it by a record with the reference as image 1 takes that record's refined (x2, y2)
//    exactly; other links are followed breadth first from the reference, moving the position by the
//    refined offset: through a record (image1 = u, image2 = v), v = x2 + (pos(u) - kp(u)); through a
//    reversed record, u = kp(u) - (x2 - pos(v)). Shortest paths first, then file and record order.
//  - keypoint positions: image 1's is (x1, y1); image 2's is (kx2, ky2) when the file has these
//    columns, else (x2, y2).
// The output holds the tracks with a position in every image of `images` and at least `min_views`
// views, sorted by reference keypoint id; track ids count from 0. Deterministic.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "tpkit/core/formats.hpp"

namespace tpkit {

struct ChainOptions {
  std::vector<std::string> images;  // output image order (paths as in the files' headers); empty = first appearance
  int min_views = 3;
  double same_position = 0.01;      // pixels
};

struct ChainStats {
  std::map<int, long> by_length;    // number of views -> tracks (after conflict handling)
  long components = 0;
  long dropped_reference_conflicts = 0;
  long views_dropped_conflicts = 0;
  long merged_duplicates = 0;
  long written = 0;
};

Tracks chain_tracks(const std::vector<Matches>& files, const ChainOptions& o, ChainStats* stats = nullptr);

}  // namespace tpkit
