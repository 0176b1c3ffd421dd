// Tiled SIFT on the real Pléiades crop: ids do not depend on the thread count, interior keypoints do
// not depend on the tiling, nodata is honoured; percentile stretch and the tile grid; descriptor
// matching's ratio / mutual rules and the grid filter.
#include "tpkit/match/sift_tiles.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>
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

// A window of a raster renders as the rendering of its crop, pixel for pixel: grey levels rounded half
// up, clipped at both ends, NaN 0 and invalid; a window outside the raster is refused.
TEST(ImageTiles, WindowRendersAsItsCrop) {
  Raster r;
  r.x0 = 300, r.y0 = 40, r.width = 257, r.height = 131;
  r.data.resize(static_cast<size_t>(r.width * r.height));
  for (size_t i = 0; i < r.data.size(); ++i) r.data[i] = static_cast<float>((i * 7919) % 1300) - 50.f;  // below lo, above hi
  for (size_t i = 0; i < r.data.size(); i += 37) r.data[i] = std::nanf("");
  const Stretch st{100.0, 1100.0, 0};
  const long x0 = 311, y0 = 45, w = 201, h = 117;
  std::vector<uint8_t> valid, crop_valid;
  const std::vector<uint8_t> u8 = render_u8(r, x0, y0, w, h, st, &valid);
  const std::vector<uint8_t> want = render_u8(crop_region(r, x0, y0, w, h), st, &crop_valid);
  ASSERT_EQ(u8.size(), static_cast<size_t>(w * h));
  EXPECT_EQ(u8, want);
  EXPECT_EQ(valid, crop_valid);
  for (long y = 0; y < h; y += 13)
    for (long x = 0; x < w; x += 11) {
      const float v = r.at(x0 - r.x0 + x, y0 - r.y0 + y);
      const double g = std::clamp((v - 100.0) * 255.0 / 1000.0, 0.0, 255.0);
      EXPECT_EQ(u8[static_cast<size_t>(y * w + x)], std::isnan(v) ? 0 : static_cast<int>(std::floor(g + 0.5)));
      EXPECT_EQ(valid[static_cast<size_t>(y * w + x)], std::isnan(v) ? 0 : 255);
    }
  long zeros = 0, full = 0;
  for (uint8_t v : u8) zeros += v == 0, full += v == 255;
  EXPECT_GT(zeros, 100);  // NaN and below lo
  EXPECT_GT(full, 100);   // above hi
  EXPECT_THROW(render_u8(r, x0, y0, w + 100, h, st), std::invalid_argument);
  EXPECT_THROW(render_u8(r, r.x0 - 1, y0, 10, 10, st), std::invalid_argument);
}

// Gathering: the keypoints of a band of tiles in (y, x, ...) order, their descriptors and ids with
// them, whether each tile comes in that order (a merge) or not (a sort).
TEST(SiftTiles, GatheringOrdersEachBandWhateverTheTilesOrder) {
  const std::vector<Tile> tiles = tile_grid(400, 400, 200, 16);  // two bands of two tiles
  ASSERT_EQ(tiles.size(), 4u);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  auto make = [&](bool sorted) {
    std::vector<Keypoints> per(tiles.size());
    for (size_t t = 0; t < tiles.size(); ++t) {
      const Tile& T = tiles[t];
      std::vector<cv::KeyPoint> kp;
      for (int k = 0; k < 300; ++k)
        kp.emplace_back(T.cx0 + u(rng) * (T.cx1 - T.cx0 - 1), std::floor(T.cy0 + u(rng) * (T.cy1 - T.cy0 - 1)), 2.f + k % 3);
      if (sorted)
        std::stable_sort(kp.begin(), kp.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
          return a.pt.y != b.pt.y ? a.pt.y < b.pt.y : a.pt.x != b.pt.x ? a.pt.x < b.pt.x : a.size < b.size;
        });
      per[t].kp = kp;
      per[t].desc.create(static_cast<int>(kp.size()), 128, CV_8U);
      for (int k = 0; k < static_cast<int>(kp.size()); ++k) {
        per[t].id.push_back(static_cast<long long>(t) * kIdsPerTile + k);
        for (int c = 0; c < 128; ++c) per[t].desc.at<uint8_t>(k, c) = static_cast<uint8_t>(static_cast<int>(kp[k].pt.x * 3 + kp[k].pt.y + c) & 255);
      }
    }
    return per;
  };
  for (bool sorted : {true, false}) {
    const Keypoints K = gather_tiles(make(sorted), tiles, Stretch{});
    ASSERT_EQ(K.kp.size(), 1200u);
    for (size_t i = 1; i < K.kp.size(); ++i) {
      const cv::KeyPoint &p = K.kp[i - 1], &q = K.kp[i];
      ASSERT_TRUE(p.pt.y < q.pt.y || (p.pt.y == q.pt.y && (p.pt.x < q.pt.x || (p.pt.x == q.pt.x && p.size <= q.size)))) << sorted << " at " << i;
    }
    for (size_t i = 0; i < K.kp.size(); ++i)  // each descriptor and id travelled with its keypoint
      for (int c = 0; c < 128; c += 31)
        ASSERT_EQ(K.desc.at<uint8_t>(static_cast<int>(i), c), static_cast<uint8_t>(static_cast<int>(K.kp[i].pt.x * 3 + K.kp[i].pt.y + c) & 255));
    std::set<long long> ids(K.id.begin(), K.id.end());
    EXPECT_EQ(ids.size(), 1200u);
  }
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
