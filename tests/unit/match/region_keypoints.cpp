// Keypoint ids do not depend on the part of the image a run detects: the tiles of a region, detected
// alone (and through the per-tile cache), give exactly the keypoints, ids and descriptors of those
// tiles in a whole-image run; ids are tile * kIdsPerTile + rank.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <map>

#include "tpkit/match/keypoint_cache.hpp"
#include "tpkit/match/sift_tiles.hpp"

using namespace tpkit;

namespace {
const std::string kImg = std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille/img_01.tif";

void expect_subset(const Keypoints& whole, const Keypoints& part, const std::vector<Tile>& tiles) {
  std::map<long long, size_t> at;
  for (size_t i = 0; i < whole.id.size(); ++i) at[whole.id[i]] = i;
  size_t expected = 0;
  for (size_t i = 0; i < whole.id.size(); ++i)
    for (const Tile& t : tiles)
      if (whole.id[i] / kIdsPerTile == t.index) ++expected;
  ASSERT_EQ(part.kp.size(), expected);
  for (size_t j = 0; j < part.kp.size(); ++j) {
    ASSERT_TRUE(at.count(part.id[j])) << part.id[j];
    const size_t i = at[part.id[j]];
    EXPECT_EQ(whole.kp[i].pt, part.kp[j].pt);
    EXPECT_EQ(whole.kp[i].size, part.kp[j].size);
    EXPECT_EQ(cv::norm(whole.desc.row(static_cast<int>(i)), part.desc.row(static_cast<int>(j))), 0.0);
  }
}
}  // namespace

TEST(RegionKeypoints, TilesMeeting) {
  const auto grid = tile_grid(1000, 1000, 250, 16);  // 4 x 4 cores of 250
  const auto t = tiles_meeting(grid, 260, 10, 300, 20);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].index, 1);
  EXPECT_EQ(tiles_meeting(grid, -0.5, -0.5, 999.5, 999.5).size(), 16u);
  EXPECT_EQ(tiles_meeting(grid, 249, 249, 251, 251).size(), 4u);  // a window across the corner of four cores
}

TEST(RegionKeypoints, SubsetOfTilesIsTheWholeRunsSlow) {
  ASSERT_TRUE(std::filesystem::exists(kImg)) << "missing " << kImg;
  const ImageSource s = open_image_source(kImg, 0, std::nullopt, "");
  SiftOptions o;
  o.tile = 512;
  const Keypoints whole = detect_sift_tiles(s, o, 2);
  ASSERT_GT(whole.kp.size(), 5000u);
  for (size_t i = 0; i < whole.id.size(); ++i) {
    ASSERT_GE(whole.id[i], 0);
    ASSERT_LT(whole.id[i] / kIdsPerTile, 4);
  }
  const auto grid = tile_grid(s.info.width, s.info.height, o.tile, o.overlap);
  const std::vector<Tile> part = {grid[1], grid[3]};
  const Stretch st = percentile_stretch(s, o.stretch_lo, o.stretch_hi);
  expect_subset(whole, detect_sift_tile_set(s, o, st, part, 1), part);
  // the per-tile cache: first run detects and writes, second reads; both the same keypoints
  const auto dir = std::filesystem::temp_directory_path() / ("tpkit_region_cache_" + std::to_string(::getpid()));
  long cached = -1;
  expect_subset(whole, detect_sift_tiles_cached(s, o, st, part, 2, dir.string(), &cached), part);
  EXPECT_EQ(cached, 0);
  expect_subset(whole, detect_sift_tiles_cached(s, o, st, {grid[3]}, 2, dir.string(), &cached), {grid[3]});
  EXPECT_EQ(cached, 1);
  std::filesystem::remove_all(dir);
}
