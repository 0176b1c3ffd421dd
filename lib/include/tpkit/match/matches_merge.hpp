// Several matches files of one pair (the regions of a tiled run, overlapping or not) combined into one
// (tp-merge). The files must name the same two images (path, width, height), the same detectors
// (detector1 / detector2 metadata: the keypoint ids mean the same) and the same columns.
//
// A match is the pair of keypoint ids (id1, id2). Records of the same match in several files are one
// (a duplicate) when their positions agree (x1 y1 x2 y2 within `same_position` pixels); records of
// one match at positions farther apart are a conflict. Conflicts -- those, an id1 matched to different
// id2 in different files, or an id2 to different id1 -- keep the record whose image-1 position lies farthest inside the region of its
// file (the `region` metadata of tp-match --region; a file without one counts as the whole image):
// that run saw the most context around the keypoint. Ties go to the earlier file. Output sorted by
// (id1, id2). Deterministic.
#pragma once
#include <vector>

#include "tpkit/core/formats.hpp"

namespace tpkit {

struct MergeOptions {
  double same_position = 0.01;  // pixels: records of one match closer than this in x1 y1 x2 y2 are one
};

struct MergeStats {
  long files = 0, records = 0, duplicates = 0, conflicts = 0, written = 0;
};

// Throws InputError naming the file when a file does not belong to the pair of the first.
Matches merge_matches(const std::vector<Matches>& files, MergeStats* stats = nullptr, const MergeOptions& o = {});

}  // namespace tpkit
