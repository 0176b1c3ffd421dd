#include "tpkit/match/match_region.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "tpkit/core/error.hpp"
#include "tpkit/match/keypoint_cache.hpp"
#include "tpkit/core/text_table.hpp"

namespace tpkit {

namespace {

std::array<double, 4> clipped(const std::array<double, 4>& w, const ImageSource& s) {
  return {std::max(-0.5, w[0]), std::max(-0.5, w[1]), std::min(s.info.width - 0.5, w[2]), std::min(s.info.height - 0.5, w[3])};
}

// Detects the tiles of `s` meeting window w (pixel-centre coordinates) and keeps the keypoints inside it.
Keypoints window_keypoints(const ImageSource& s, const PairMatchOptions& o, const Stretch& st, const std::array<double, 4>& w,
                           long* tiles, long* cached) {
  const std::vector<Tile> grid = tile_grid(s.info.width, s.info.height, o.sift.tile, o.sift.overlap);
  const std::vector<Tile> need = tiles_meeting(grid, w[0], w[1], w[2], w[3]);
  *tiles = static_cast<long>(need.size());
  return detect_sift_tiles_cached(s, o.sift, st, need, o.threads, o.cache_dir, cached, &w);
}

}  // namespace

Matches match_region(const ImageSource& a, const ImageSource& b, const PairGeometry& G, const PairMatchOptions& o,
                     const RegionOptions& r, PairMatchStats* stats, RegionStats* rstats) {
  const auto& w = r.window;
  if (w[2] <= 0 || w[3] <= 0) throw UsageError("--region: width and height must be > 0");
  if (w[0] < 0 || w[1] < 0 || w[0] + w[2] > a.info.width || w[1] + w[3] > a.info.height)
    throw UsageError("--region " + std::to_string(w[0]) + " " + std::to_string(w[1]) + " " + std::to_string(w[2]) + " " +
                     std::to_string(w[3]) + " is not inside " + a.path + " (" + std::to_string(a.info.width) + "x" +
                     std::to_string(a.info.height) + ")");
  const auto t0 = std::chrono::steady_clock::now();
  RegionStats rs;
  PairMatchStats st;
  const std::array<double, 4> grown1 =
      clipped({w[0] - 0.5 - r.margin, w[1] - 0.5 - r.margin, w[0] + w[2] - 0.5 + r.margin, w[1] + w[3] - 0.5 + r.margin}, a);
  Keypoints K1 = window_keypoints(a, o, G.stretch1, grown1, &rs.tiles1, &rs.cached_tiles1);
  rs.window2 = clipped(image2_window(G, grown1, r.margin), b);
  Keypoints K2;
  if (rs.window2[0] < rs.window2[2] && rs.window2[1] < rs.window2[3])
    K2 = window_keypoints(b, o, G.stretch2, rs.window2, &rs.tiles2, &rs.cached_tiles2);
  const double detect_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  PairMatchOptions ow = o;
  ow.window = {w[0] - 0.5, w[1] - 0.5, w[0] + w[2] - 0.5, w[1] + w[3] - 0.5};
  Matches M = match_keypoints(a, b, std::move(K1), std::move(K2), ow, &st);
  rs.matched = st.gridded;
  st.seconds[0] = detect_s;
  st.cached1 = rs.tiles1 > 0 && rs.cached_tiles1 == rs.tiles1;
  st.cached2 = rs.tiles2 > 0 && rs.cached_tiles2 == rs.tiles2;
  meta_set(M.meta, "region", std::to_string(w[0]) + " " + std::to_string(w[1]) + " " + std::to_string(w[2]) + " " +
                                 std::to_string(w[3]) + " (x0 y0 width height, image1 pixels; margin " + format_number(r.margin) +
                                 " px: " + std::to_string(rs.matched) + " verified matches in the grown window, " +
                                 std::to_string(st.in_window) + " in the region, " + std::to_string(M.size()) + " refined)");
  meta_set(M.meta, "region-read", std::to_string(rs.tiles1) + " detection tiles of image1, " + std::to_string(rs.tiles2) +
                                      " of image2 in x " + format_number(std::round(rs.window2[0])) + ".." +
                                      format_number(std::round(rs.window2[2])) + " y " + format_number(std::round(rs.window2[1])) +
                                      ".." + format_number(std::round(rs.window2[3])));
  if (stats) *stats = st;
  if (rstats) *rstats = rs;
  return M;
}

}  // namespace tpkit
