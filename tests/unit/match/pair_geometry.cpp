// The pair geometry decodes each image once, for its decimated copy and for the samples of its stretch:
// the stretch it writes is percentile_stretch's, also when the height is not a multiple of the
// decimation (the rows below the last whole block are sampled too) and when it is.
#include "tpkit/match/pair_geometry.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "tpkit/match/image_tiles.hpp"

using namespace tpkit;

namespace {
const std::string kDir = std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille/";

void expect_same(const Stretch& a, const Stretch& b) {
  EXPECT_EQ(a.lo, b.lo);
  EXPECT_EQ(a.hi, b.hi);
  EXPECT_EQ(a.valid_samples, b.valid_samples);
}
}  // namespace

TEST(PairGeometry, StretchIsThePercentileStretchOfTheWholeImage) {
  ASSERT_TRUE(std::filesystem::exists(kDir + "img_01.tif")) << "missing " << kDir;
  const ImageSource a = open_image_source(kDir + "img_01.tif", 0, std::nullopt, "");
  const ImageSource b = open_image_source(kDir + "img_02.tif", 0, std::nullopt, "");
  SiftOptions sift;
  const Stretch s1 = percentile_stretch(a, sift.stretch_lo, sift.stretch_hi);
  const Stretch s2 = percentile_stretch(b, sift.stretch_lo, sift.stretch_hi);
  ASSERT_LT(s1.lo, s1.hi);
  // 1024 rows: decimated by 3 (341 blocks and a row left over) and by 2 (none left)
  for (long side : {350L, 512L}) {
    PairGeometryOptions g;
    g.max_side = side;
    const PairGeometry G = estimate_pair_geometry(a, b, sift, g);
    ASSERT_EQ(G.scale1, side == 350 ? 3 : 2);
    expect_same(G.stretch1, s1);
    expect_same(G.stretch2, s2);
  }
  // the stages on strips whose height (299 rows) is no multiple of the step (3): the rows sampled are
  // counted from the image's first row, not the strip's
  std::vector<float> samples;
  const long step = stretch_step(a.info.width, a.info.height, 200000);
  ASSERT_EQ(step, 3);
  for (long y = 0; y < a.info.height; y += 299)
    add_stretch_samples(read_valid_region(a, 0, y, a.info.width, 299), step, samples);
  expect_same(stretch_of_samples(samples, sift.stretch_lo, sift.stretch_hi, a),
              percentile_stretch(a, sift.stretch_lo, sift.stretch_hi, 200000));
}
