// tp-chain --coverage: the coverage figure (core/coverage_plot.hpp) of a chainer's tracks, one panel per
// image of the output, over the images' thumbnails.
#pragma once
#include <string>

#include "tpkit/match/tracks_chain.hpp"

namespace tpkit {

// After join(): writes the SVG atomically.
void save_tracks_coverage(const std::string& path, const TrackChainer& chainer);

}  // namespace tpkit
