// Views of multi-view tracks that the others contradict through the images' RPC models (tp-chain
// --rpc-check): the geometric counterpart of the loop closure, which only sees records that disagree
// with each other and cannot judge a track of two views, or a view whose records all agree on a wrong
// point.
//
// For every pair of images (a, b), a < b, and every track seen in both: the signed distance across
// the curve of view b (pixels of image b) from the RPC epipolar curve of view a over the heights both
// models are valid for (3 heights; positive to the left of the curve run from low to high heights).
// Delivered models are biased: per pair, a plane in (x_a, y_a) of these distances (a constant below
// 10 tracks) is fitted to them robustly (least squares, then twice on those within max(threshold,
// 3 x the robust sigma (1.4826 x MAD) of the residuals)); the residual of the plane is what a pair of
// views is judged by: it disagrees when |residual| > max(threshold, 4 x the pair's robust sigma).
// Pairs seen by fewer than 3 tracks are not judged.
// Per track, while a pair of its views disagrees: the view that disagrees with the most others (ties:
// the larger sum of |residual| / tolerance, then the later image) loses its place; a track left with
// two views that disagree loses both. Tracks left with fewer than min_views views are removed (ids
// renumbered from 0). Positions are pixels (x = column, y = row, (0, 0) the centre of the top-left
// pixel) in both images, as the models use them.
#pragma once
#include <vector>

#include "tpkit/core/formats.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

struct EpipolarCheckOptions {
  double threshold = 1.0;  // pixels: the least tolerance of a pair's residual
  int min_views = 2;       // fewest views of a track kept
  int threads = 1;
};

struct EpipolarCheckStats {
  long pairs_judged = 0;      // image pairs with a bias estimated
  double median_sigma = 0;    // median over them of the robust sigma of the residuals, pixels
  double largest_bias = 0;    // largest |bias| (plane at the pair's tracks' mean position), pixels
  long views_dropped = 0;
  long tracks_removed = 0;    // left with fewer than min_views views
  std::vector<long> views_dropped_by_length;  // index: the track's views before the check
};

// `models[k]`: the model of image k of `t` (nullptr: its pairs are not judged). Throws nothing for
// pairs whose models share no heights (not judged).
EpipolarCheckStats epipolar_check(Tracks& t, const std::vector<const RpcModel*>& models, const EpipolarCheckOptions& o);
// The header lines that say so: `# rpc_check:` (the figures) and `# tracks_by_views:` counted again.
void note_epipolar_check(Tracks& t, const EpipolarCheckStats& st, double threshold);

}  // namespace tpkit
