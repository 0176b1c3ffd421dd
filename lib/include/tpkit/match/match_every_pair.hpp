// tp-match on every pair of several images in one process: each image is detected once
// (detect_sift_cached), and each pair i < j goes through match_keypoints as in a pairwise run, so
// its file is the same as `tp-match IMG_i IMG_j`'s.
//
// Scheduling with o.threads = T: whole groups of T images are detected one image per thread (parallel
// over images scales better than inside one detector), the remaining images share the threads. Pairs
// are matched in order (0,1), (0,2), ..., (1,2), ... on the calling thread as soon as both images are
// detected, so that the first pairs overlap the detection of the last images instead of leaving
// threads idle; a pair that starts while detection still runs gets the threads detection leaves free
// (at least one) and all T from its next refinement band once detection ends; later pairs get T.
// With T = 1 everything runs in sequence.
#pragma once
#include <functional>
#include <vector>

#include "tpkit/match/match_pair.hpp"

namespace tpkit {

// on_pair(i, j, matches, stats) is called on the calling thread, in pair order; stats.cached1/2 tell
// whether the keypoints came from the cache. detect_seconds (may be null): wall time from the call to
// the end of the last detection. rpc (empty, or one entry per image, null for none): a pair whose two
// images have models is searched along the RPC epipolar curves (PairMatchOptions::rpc1/rpc2). The first error (detection or matching) is rethrown once every
// thread has stopped.
void match_every_pair(const std::vector<ImageSource>& src, const PairMatchOptions& o,
                      const std::vector<const RpcModel*>& rpc,
                      const std::function<void(size_t i, size_t j, Matches& m, const PairMatchStats& st)>& on_pair,
                      double* detect_seconds = nullptr);

}  // namespace tpkit
