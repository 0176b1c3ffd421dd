// tp-chain --coverage and tp-match --coverage: the coverage figure (core/coverage_plot.hpp) of a chainer's
// tracks (one panel per image of the output) or of a pair's matches (two panels), over the images'
// thumbnails.
#pragma once
#include <string>

#include "tpkit/match/tracks_chain.hpp"

namespace tpkit {

// After join(): writes the SVG atomically.
void save_tracks_coverage(const std::string& path, const TrackChainer& chainer);
// The matches of one pair: image 1's points (x1, y1) and image 2's (x2, y2). Writes the SVG atomically.
void save_matches_coverage(const std::string& path, const Matches& matches);

}  // namespace tpkit
