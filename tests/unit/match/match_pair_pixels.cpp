// The refinement's pixels (match_pair.cpp, RefinePixels): a pair whose images are held whole (the default
// up to 4096²) and the same pair read as images too large to hold (whole_image_pixels 0: the final pass
// band by band, the blur and high-pass estimates' samples window by window) choose the same blur and
// high-pass, with the same sample scores to within the filters' edge effects, and give the same records.
#include <gtest/gtest.h>
#include <unistd.h>

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
  windows.whole_image_pixels = 0;
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
  fs::remove_all(dir);
}
