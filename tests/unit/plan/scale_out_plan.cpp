// tp-plan's pieces: shell quoting, regions, pairs from footprints, the jobs and the Makefile text.
#include "tpkit/plan/scale_out_plan.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include "tpkit/core/error.hpp"
#include "tpkit/match/sift_tiles.hpp"

using namespace tpkit;

TEST(ScaleOutPlan, ShellQuote) {
  EXPECT_EQ(shell_quote("a b"), "'a b'");
  EXPECT_EQ(shell_quote("it's"), "'it'\\''s'");
  EXPECT_EQ(shell_quote("$x `y` \"z\""), "'$x `y` \"z\"'");
  EXPECT_THROW(shell_quote("a\nb"), UsageError);
}

TEST(ScaleOutPlan, RegionsCoverTheImage) {
  const auto r = plan_regions(1000, 600, 400, 0);
  ASSERT_EQ(r.size(), 6u);  // 3 x 2
  EXPECT_EQ(r[2], (std::array<long, 4>{800, 0, 200, 400}));
  EXPECT_EQ(r[5], (std::array<long, 4>{800, 400, 200, 200}));
  const auto o = plan_regions(1000, 600, 400, 16);
  EXPECT_EQ(o[4], (std::array<long, 4>{384, 384, 432, 216}));
}

TEST(ScaleOutPlan, PairsFromFootprints) {
  PlanImage a{"/a", 10, 10, std::nullopt}, b{"/b", 10, 10, Footprint{{{{0, 0}}, {{1, 1}}}}},
      c{"/c", 10, 10, Footprint{{{{2, 2}}, {{3, 3}}}}}, d{"/d", 10, 10, Footprint{{{{0.5, 0.5}}, {{2.5, 2.5}}}}};
  EXPECT_TRUE(footprints_may_overlap(a, b));  // unknown footprint: paired
  EXPECT_FALSE(footprints_may_overlap(b, c));
  EXPECT_TRUE(footprints_may_overlap(b, d));
  PlanOptions o;
  o.work = "/w d";
  o.tile = 256;
  const Plan p = make_plan({b, c, d}, o);
  ASSERT_EQ(p.pairs.size(), 2u);  // (b, d), (c, d)
  EXPECT_EQ(p.pairs[0], (std::array<size_t, 2>{0, 2}));
  EXPECT_EQ(p.pairs[1], (std::array<size_t, 2>{1, 2}));
  EXPECT_EQ(p.geometry.size(), 2u);
  EXPECT_EQ(p.tiles.size(), 2u);
  EXPECT_EQ(p.tiles[1].command,
            "tp-match -q --threads 1 --tile 768 --geometry '/w d/geometry/pair-2-3.geometry' --region 0 0 10 10 --cache '/w d/cache' "
            "-o '/w d/tiles/pair-2-3/tile-1.matches' '/c' '/d'");
  // each image once, through its first pair's geometry (d is image 2 of pair (b, d))
  ASSERT_EQ(p.detect.size(), 3u);
  EXPECT_EQ(p.detect[2].command,
            "tp-match -q --threads 1 --tile 768 --geometry '/w d/geometry/pair-1-3.geometry' --detect 2 --region 0 0 10 10 "
            "--cache '/w d/cache' -o '/w d/detect/image-3/block-1.detection' '/b' '/d'");
  // a region job needs the geometry and the detections of its own two images only (the plan grows as
  // pairs x regions, not pairs x regions x images)
  EXPECT_EQ(p.tiles[1].depends, (std::vector<std::string>{"geometry/pair-2-3.geometry"}));
  EXPECT_EQ(p.tiles[1].detections, (std::vector<size_t>{1, 2}));
  EXPECT_EQ(p.image_detections[2], (std::vector<std::string>{"detect/image-3/block-1.detection"}));
  EXPECT_EQ(p.merge[0].depends, (std::vector<std::string>{"tiles/pair-1-3/tile-1.matches"}));
  EXPECT_EQ(p.chain[0].command,
            "tp-chain -q --images '/b' '/c' '/d' -o '/w d/tracks.tracks' '/w d/pairs/pair-1-3.matches' '/w d/pairs/pair-2-3.matches'");
}

TEST(ScaleOutPlan, MakefileDoublesDollars) {
  PlanImage a{"/x/$a", 300, 300, std::nullopt}, b{"/x/b", 300, 300, std::nullopt};
  PlanOptions o;
  o.work = "/w";
  const std::string mk = plan_makefile(make_plan({a, b}, o));
  EXPECT_NE(mk.find("'/x/$$a'"), std::string::npos);
  EXPECT_EQ(mk.find("'/x/$a'"), std::string::npos);
  EXPECT_NE(mk.find("detect/image-2/block-1.detection: geometry/pair-1-2.geometry\n\t"), std::string::npos);
  EXPECT_NE(mk.find("detect-image-1 := detect/image-1/block-1.detection\n"), std::string::npos);
  EXPECT_NE(mk.find("tiles/pair-1-2/tile-1.matches: geometry/pair-1-2.geometry $(detect-image-1) $(detect-image-2)\n\t"),
            std::string::npos);
  EXPECT_NE(mk.find("pairs/pair-1-2.matches: tiles/pair-1-2/tile-1.matches\n"), std::string::npos);
  EXPECT_THROW(make_plan({a}, o), UsageError);
}

// The detect stage: every detection tile of every image in exactly one job, and no job without one.
TEST(ScaleOutPlan, DetectionTilesOnce) {
  PlanImage a{"/a", 5000, 3000, std::nullopt}, b{"/b", 4000, 4100, std::nullopt};
  for (long detect_tile : {0L, 512L, 768L, 3000L}) {
    PlanOptions o;
    o.work = "/w";
    o.tile = 1100;
    o.detect_tile = detect_tile;
    const Plan p = make_plan({a, b}, o);
    for (size_t i = 0; i < 2; ++i) {
      const PlanImage& im = i == 0 ? a : b;
      const auto grid = tile_grid(im.width, im.height, detect_tile > 0 ? detect_tile : SiftOptions{}.tile, 0);
      std::vector<int> seen(grid.size(), 0);
      long jobs = 0;
      for (const PlanJob& j : p.detect) {
        if (j.target.rfind("detect/image-" + std::to_string(i + 1) + "/", 0) != 0) continue;
        ++jobs;
        long x, y, w, h;
        const size_t at = j.command.find("--region ");
        ASSERT_NE(at, std::string::npos);
        ASSERT_EQ(std::sscanf(j.command.c_str() + at, "--region %ld %ld %ld %ld", &x, &y, &w, &h), 4);
        const auto t = tiles_starting_in(grid, x, y, w, h);
        EXPECT_FALSE(t.empty()) << j.command;
        for (const Tile& k : t) ++seen[static_cast<size_t>(k.index)];
      }
      EXPECT_GT(jobs, 0);
      for (int s : seen) EXPECT_EQ(s, 1) << "detect tile " << detect_tile << ", image " << i + 1;
    }
  }
}
