// Tiled SIFT on the real Pléiades crop: ids do not depend on the thread count, interior keypoints do
// not depend on the tiling, nodata is honoured; percentile stretch and the tile grid; descriptor
// matching's ratio / mutual rules and the grid filter.
#include "tpkit/match/sift_tiles.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "tpkit/core/error.hpp"
#include "tpkit/match/match_descriptors.hpp"

using namespace tpkit;

namespace {
const std::string kImg = std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille/img_01.tif";
}

TEST(ImageTiles, GridCoversOnceWithOverlap) {
  auto tiles = tile_grid(1000, 700, 300, 20);
  ASSERT_EQ(tiles.size(), 6u);  // round(1000 / 300) x round(700 / 300)
  std::vector<int> cover(1000 * 700, 0);
  for (const auto& t : tiles) {
    for (long y = t.cy0; y < t.cy1; ++y)
      for (long x = t.cx0; x < t.cx1; ++x) cover[y * 1000 + x]++;
    EXPECT_EQ(t.rx0, std::max(0L, t.cx0 - 20));
    EXPECT_EQ(t.ry1, std::min(700L, t.cy1 + 20));
  }
  for (int c : cover) ASSERT_EQ(c, 1);
}

TEST(ImageTiles, StretchAndNodata) {
  auto dir = std::filesystem::temp_directory_path() / ("tpkit_tiles_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const long W = 200, H = 100;
  std::vector<uint16_t> px(W * H);
  for (long i = 0; i < W * H; ++i) px[i] = static_cast<uint16_t>(i % 1000 + 100);  // uniform 100..1099
  for (long x = 0; x < W; ++x) px[x] = 0;                                            // first row nodata
  std::string path = (dir / "a.tif").string();
  write_image_u16(path, W, H, px);
  ImageSource s = open_image_source(path, 0, 0.0, "");
  Stretch st = percentile_stretch(s, 1, 99);
  EXPECT_NEAR(st.lo, 110, 3);
  EXPECT_NEAR(st.hi, 1089, 3);
  Raster r = read_valid_region(s, 0, 0, W, 2);
  EXPECT_TRUE(std::isnan(r.at(5, 0)));
  EXPECT_FALSE(std::isnan(r.at(5, 1)));
  std::vector<uint8_t> valid;
  auto u8 = render_u8(r, st, &valid);
  EXPECT_EQ(valid[5], 0);
  EXPECT_EQ(valid[W + 5], 255);
  // all nodata
  std::vector<uint16_t> zero(W * H, 0);
  std::string zpath = (dir / "z.tif").string();
  write_image_u16(zpath, W, H, zero);
  EXPECT_THROW(percentile_stretch(open_image_source(zpath, 0, 0.0, ""), 1, 99), InputError);
  EXPECT_THROW(open_image_source(zpath, 1, std::nullopt, ""), InputError);  // no band 2
  std::filesystem::remove_all(dir);
}

TEST(DescriptorMatch, RatioMutualAndGrid) {
  // d2 holds each d1 row slightly perturbed, plus a near-duplicate of row 0 (ambiguous: fails the ratio)
  cv::RNG rng(1);
  cv::Mat d1(50, 128, CV_32F), d2(51, 128, CV_32F);
  rng.fill(d1, cv::RNG::UNIFORM, 0, 100);
  for (int i = 0; i < 50; ++i) {
    cv::Mat noise(1, 128, CV_32F);
    rng.fill(noise, cv::RNG::NORMAL, 0, 2);
    cv::Mat row = d1.row(i) + noise;
    row.copyTo(d2.row(49 - i));
  }
  d2.row(49).copyTo(d2.row(50));
  d2.at<float>(50, 0) += 1;
  DescriptorMatchOptions o;
  auto m = match_descriptors(d1, d2, o);
  EXPECT_EQ(m.size(), 49u);
  for (const auto& x : m) {
    EXPECT_NE(x.i1, 0);
    EXPECT_EQ(x.i2, 49 - x.i1);
    EXPECT_LT(x.ratio, 0.8f);
  }
  o.exact_below = 0;  // approximate search gives the same answer on this easy set
  EXPECT_EQ(match_descriptors(d1, d2, o).size(), 49u);
  std::vector<cv::Point2f> pts;
  std::vector<float> score;
  for (int i = 0; i < 100; ++i) {
    pts.emplace_back(static_cast<float>(i % 10) * 10 + 1, static_cast<float>(i / 10) * 10 + 1);
    score.push_back(static_cast<float>(i));
  }
  auto keep = grid_select(pts, score, 100, 100, 2, 3);
  EXPECT_EQ(keep.size(), 12u);
  EXPECT_EQ(keep[0], 0u);
}

TEST(SiftTiles, IdsStableAcrossThreadsAndTilingSlow) {
  if (!std::filesystem::exists(kImg)) GTEST_SKIP() << "no " << kImg;
  ImageSource s = open_image_source(kImg, 0, std::nullopt, "");
  SiftOptions o;
  Keypoints a = detect_sift_tiles(s, o, 1);
  Keypoints b = detect_sift_tiles(s, o, 2);
  ASSERT_GT(a.kp.size(), 5000u);
  ASSERT_EQ(a.kp.size(), b.kp.size());
  for (size_t i = 0; i < a.kp.size(); i += 97) {
    EXPECT_EQ(a.kp[i].pt, b.kp[i].pt);
    EXPECT_EQ(a.id[i], b.id[i]);
    EXPECT_EQ(cv::norm(a.desc.row(static_cast<int>(i)), b.desc.row(static_cast<int>(i))), 0.0);
  }
  // 4 tiles of 512: keypoints away from the tile seams are found at the same positions
  SiftOptions t = o;
  t.tile = 512;
  Keypoints c = detect_sift_tiles(s, t, 2);
  EXPECT_EQ(c.tiles, 4);
  // positions agree to float rounding (tile offsets are added after detection)
  std::set<std::pair<long, long>> pc;
  auto key = [](const cv::KeyPoint& k) { return std::make_pair(std::lround(k.pt.x * 100), std::lround(k.pt.y * 100)); };
  for (const auto& k : c.kp) pc.insert(key(k));
  long interior = 0, found = 0;
  for (const auto& k : a.kp) {
    if (std::abs(k.pt.x - 511.5f) < 120 || std::abs(k.pt.y - 511.5f) < 120 || k.size > 20) continue;
    ++interior;
    found += pc.count(key(k));
  }
  ASSERT_GT(interior, 1000);
  EXPECT_GT(static_cast<double>(found) / interior, 0.97);
}
