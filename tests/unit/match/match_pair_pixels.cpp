// The refinement's pixels (match_pair.cpp, RefinePixels): a pair whose images are held in memory (the
// default up to 4096²) and the same pair read as images too large to hold (refine_hold_pixels 0: the final
// pass band by band, the blur and high-pass estimates' samples window by window) choose the same blur and
// high-pass, with the same sample scores to within the filters' edge effects, and give the same records.
// So does a region run, which holds only the part of the images its window reaches.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "tpkit/match/image_tiles.hpp"
#include "tpkit/match/match_pair.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

TEST(MatchPairPixels, WholeImagesAndWindowsGiveTheSameRefinement) {
  const fs::path dir = fs::temp_directory_path() / ("tpkit-pair-pixels-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  // view 2 blurred by 1.5 px: the blur estimate chooses a blur of view 1, so the windows are filtered
  const std::string synth = std::string(TPKIT_BIN_DIR) + "/tp-synth --out " + dir.string() +
                            " --size 384 --relief 20 --points 20 --blur 1.5 > /dev/null 2>&1";
  ASSERT_EQ(std::system(synth.c_str()), 0) << synth;
  const ImageSource a = open_image_source((dir / "view1.tif").string(), 0, std::nullopt, "");
  const ImageSource b = open_image_source((dir / "view2.tif").string(), 0, std::nullopt, "");
  PairMatchOptions whole;
  whole.threads = 2;
  PairMatchOptions windows = whole;
  windows.refine_hold_pixels = 0;
  PairMatchStats sw, sn;
  const Matches mw = match_pair(a, b, whole, &sw), mn = match_pair(a, b, windows, &sn);
  ASSERT_GT(mw.size(), 200u);
  EXPECT_GT(sw.blur.sigma, 0.5);  // image 1 blurred to meet image 2
  EXPECT_EQ(sw.blur.sigma, sn.blur.sigma);
  EXPECT_NEAR(sw.blur.score, sn.blur.score, 2e-3);
  EXPECT_EQ(sw.highpass.sigma, sn.highpass.sigma);
  EXPECT_NEAR(sw.highpass.spread_none, sn.highpass.spread_none, 0.1 * sw.highpass.spread_none);
  ASSERT_EQ(mw.size(), mn.size());
  EXPECT_EQ(mw.id1, mn.id1);
  EXPECT_EQ(mw.id2, mn.id2);
  EXPECT_EQ((mw.xy - mn.xy).cwiseAbs().maxCoeff(), 0.0);

  PairMatchOptions region = whole, region_read = windows;
  region.window = region_read.window = std::array<double, 4>{100, 120, 260, 300};
  PairMatchStats rw, rn;
  const Matches gw = match_pair(a, b, region, &rw), gn = match_pair(a, b, region_read, &rn);
  ASSERT_GT(gw.size(), 50u);
  ASSERT_LT(gw.size(), mw.size() / 2);
  for (size_t k = 0; k < gw.size(); ++k) {
    EXPECT_GE(gw.xy(static_cast<Eigen::Index>(k), 0), 99.5);
    EXPECT_LT(gw.xy(static_cast<Eigen::Index>(k), 0), 260.0);
  }
  EXPECT_EQ(rw.blur.sigma, rn.blur.sigma);
  EXPECT_EQ(rw.highpass.sigma, rn.highpass.sigma);
  ASSERT_EQ(gw.size(), gn.size());
  EXPECT_EQ(gw.id1, gn.id1);
  EXPECT_EQ((gw.xy - gn.xy).cwiseAbs().maxCoeff(), 0.0);
  fs::remove_all(dir);
}
