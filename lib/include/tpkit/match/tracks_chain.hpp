// Pairwise matches files joined into multi-view tracks (tp-chain), for any set of pairs of N images.
//
// Nodes are (image, keypoint id); every record of every file links its two nodes (union-find).
// Keypoints of one image at the same position (within `same_position` px; SIFT emits one keypoint per
// dominant orientation) are merged into one node first. A track is a connected component:
//  - images follow `images` (default: order of first appearance in the files); the reference is the
//    first of them that the track holds (column `ref`, 1-based; `kp` is its keypoint id);
//  - a track that holds two different keypoints (positions) of the reference image is dropped; one
//    that holds two different keypoints of another image loses that view (counted as a conflict);
//  - view positions refer to the reference keypoint: the reference view is its keypoint position; a
//    view linked to it by a record with the reference as image 1 takes that record's refined (x2, y2)
//    exactly; other links are followed breadth first from the reference, moving the position by the
//    refined offset: through a record (image1 = u, image2 = v), v = x2 + (pos(u) - kp(u)); through a
//    reversed record, u = kp(u) - (x2 - pos(v)). Shortest paths first, then file and record order.
//  - loop closure over every cycle of the track's links (close_loops in the source): each record is
//    compared with what all the others say (the least-squares offsets of the views without it) within
//    max(ChainOptions::closure, 5 sigma of the difference); while one disagrees, the worst is left out
//    (one cycle whose records all disagree alike: its view reached later goes); a view most of whose
//    records went (the view inconsistent with the most others) loses its place; then the positions are
//    walked again without them. A track whose reference view goes refers to its next image's keypoint.
//  - keypoint positions: image 1's is (x1, y1); image 2's is (kx2, ky2) when the file has these
//    columns, else (x2, y2).
//  - sigmas (when every file has a `sigma` column: the standard deviation of the record's (x2, y2)
//    relative to (x1, y1), px): each record's variance is split equally between its two ends; a view
//    reached over several records adds half the variance of each record on its path, and the reference
//    takes half that of the first record leaving it. Written as sigma1 ... sigmaK (nan: not seen).
// The output holds every track with at least `min_views` views among the images of `images` (a view
// it is not seen in: nan nan), sorted by reference image then reference keypoint id (a track whose
// reference view the closure dropped keeps that place); track ids count from 0. Deterministic.
//
// Memory: the files are added one at a time and not kept; per match about 28 bytes of links and 24
// per distinct keypoint, then 4-byte indices for the union-find, the adjacency and the components
// (under 100 bytes per match in all when keypoints are shared by two records on average; see
// bench_chain). The tracks are streamed out: none is held in memory.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "tpkit/core/formats.hpp"

namespace tpkit {

struct ChainOptions {
  std::vector<std::string> images;  // output image order (paths as in the files' headers); empty = first appearance
  int min_views = 3;
  double same_position = 0.01;      // pixels
  // Records marked refined 0 (tp-match kept a verified match whose refinement was rejected at its keypoint
  // position, with a larger sigma): chained only when set; else left out and counted (ChainStats, header).
  bool unrefined = false;
  // Loop closure: a record between two views of a track that the track's other records contradict
  // (over every cycle: pair 2-3 of a triplet chained through 1-2 and 1-3, or any loop of a block's
  // pairs) by more than max(closure, 5 sigma of the difference) pixels is wrong: the view inconsistent
  // with most of its partners loses its place, a lone bad record is left out (counted). 0: no check.
  double closure = 0.5;
};

struct ChainStats {
  std::map<int, long> by_length;    // number of views -> tracks (after conflict handling)
  std::map<int, long> written_by_length;
  long components = 0;
  long dropped_reference_conflicts = 0;
  long views_dropped_conflicts = 0;
  long views_dropped_closure = 0;   // views whose redundant links disagreed (ChainOptions::closure)
  long links_dropped_closure = 0;   // single records left out of a track whose views they both keep
  long merged_duplicates = 0;
  long written = 0;
  long unrefined_left_out = 0;      // records marked refined 0, not chained (ChainOptions::unrefined false)
};

// Adds matches files one by one (each may be dropped after add), joins them, writes the tracks.
class TrackChainer {
 public:
  explicit TrackChainer(const ChainOptions& o);
  ~TrackChainer();
  TrackChainer(const TrackChainer&) = delete;
  TrackChainer& operator=(const TrackChainer&) = delete;
  void add(const Matches& m);
  // The fewest views of a written track, when it depends on the files (before join()).
  void set_min_views(int n);
  // Joins every file added; the statistics are final after it. Throws when --images names an image of
  // no file or min_views exceeds the images.
  const ChainStats& join();
  // The output's images, metadata and columns (a Tracks of zero rows): after join().
  Tracks header() const;
  // Each track in output order: after join(). `xy` holds 2K coordinates (nan where not seen), `extra`
  // the values of header().extra.names.
  void for_each(const std::function<void(long long track, const double* xy, const double* extra)>& f) const;
  // header() and every track, as write_tracks would write them.
  void write(std::ostream& os) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The tracks of files held in memory (tests, benchmarks).
Tracks chain_tracks(const std::vector<Matches>& files, const ChainOptions& o, ChainStats* stats = nullptr);
// The tracks of a joined chainer in memory (header() and every track); `st`: its join()'s statistics.
Tracks chained_tracks(const TrackChainer& c, const ChainStats& st);

}  // namespace tpkit
