// epipolar_grid.hpp on the real Pléiades models of img_01 -> img_02 (tag 50844): the interpolated curve
// points agree with the exact ones (localize, then project) everywhere in the box, not only at the check
// points; a tolerance the grid cannot meet leaves it unused; points outside the box or the height range
// are refused rather than extrapolated, and so is a grid larger than the caller allows.
#include "tpkit/rpc/epipolar_grid.hpp"

#include <gtest/gtest.h>

#include <random>

#include "tpkit/rpc/rpc_io.hpp"

using namespace tpkit;

namespace {
const std::string kData = std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille/";
RpcModel model(int i) { return *read_rpc_tiff(kData + "img_0" + std::to_string(i) + ".tif"); }
Eigen::Vector2d exact(const RpcModel& a, const RpcModel& b, double x, double y, double h) {
  const Eigen::Vector2d ll = a.localize(x, y, h);
  return b.project(ll[0], ll[1], h);
}
}  // namespace

TEST(EpipolarGrid, AgreesWithTheModelsEverywhere) {
  const RpcModel a = model(1), b = model(2);
  // the whole height range tp-match searches first (both models' validity ranges), then a narrow one
  for (const auto& range : {std::pair<double, double>{40, 1090}, {41.2, 344.6}}) {
    const EpipolarGrid g(a, b, 0, 0, 1023, 1023, range.first, range.second, EpipolarGridOptions(), 2);
    ASSERT_TRUE(g.ok());
    EXPECT_LE(g.check_error(), 1e-3);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> px(0, 1023), hh(range.first, range.second);
    double worst = 0;
    for (int n = 0; n < 3000; ++n) {
      const double x = px(rng), y = px(rng), h = hh(rng);
      Eigen::Vector2d q;
      ASSERT_TRUE(g.point(x, y, h, q));
      worst = std::max(worst, (q - exact(a, b, x, y, h)).norm());
    }
    EXPECT_LE(worst, 2e-3) << "heights " << range.first << ".." << range.second;
    // the nodes themselves are exact
    Eigen::Vector2d q;
    ASSERT_TRUE(g.point(0, 0, range.first, q));
    EXPECT_LT((q - exact(a, b, 0, 0, range.first)).norm(), 1e-9);
  }
}

TEST(EpipolarGrid, RefinesOrGivesUp) {
  const RpcModel a = model(1), b = model(3);
  EpipolarGridOptions o;
  o.spacing = 512;  // too coarse for 1e-4 px: rebuilt finer until it holds
  o.levels = 2;
  o.tolerance = 1e-4;
  o.refinements = 6;
  const EpipolarGrid fine(a, b, 0, 0, 1023, 1023, 40, 1090, o, 2);
  ASSERT_TRUE(fine.ok());
  EXPECT_LT(fine.spacing(), 512);
  EXPECT_LE(fine.check_error(), 1e-4);
  o.tolerance = 1e-12;  // no grid meets it within two refinements
  o.refinements = 2;
  const EpipolarGrid none(a, b, 0, 0, 1023, 1023, 40, 1090, o, 2);
  EXPECT_FALSE(none.ok());
  EXPECT_GT(none.check_error(), 1e-12);
  Eigen::Vector2d q;
  EXPECT_FALSE(none.point(500, 500, 300, q));
}

TEST(EpipolarGrid, RefusesOutsideItsBoxAndHeights) {
  const RpcModel a = model(1), b = model(2);
  const EpipolarGrid g(a, b, 100, 200, 600, 700, 50, 400, EpipolarGridOptions(), 1);
  ASSERT_TRUE(g.ok());
  Eigen::Vector2d q;
  EXPECT_TRUE(g.point(100, 700, 400, q));
  EXPECT_FALSE(g.point(99.9, 300, 100, q));
  EXPECT_FALSE(g.point(300, 700.1, 100, q));
  EXPECT_FALSE(g.point(300, 300, 49, q));
  EXPECT_FALSE(g.point(300, 300, 401, q));
  // a grid of more nodes than allowed is not built (9 x 9 x 9 here)
  EpipolarGridOptions few;
  few.max_nodes = 700;
  EXPECT_FALSE(EpipolarGrid(a, b, 0, 0, 1023, 1023, 50, 400, few, 1).ok());
  few.max_nodes = 729;
  EXPECT_TRUE(EpipolarGrid(a, b, 0, 0, 1023, 1023, 50, 400, few, 1).ok());
  // an empty height range or box builds nothing
  EXPECT_FALSE(EpipolarGrid(a, b, 0, 0, 100, 100, 300, 300, EpipolarGridOptions(), 1).ok());
  EXPECT_FALSE(EpipolarGrid(a, b, 10, 0, 5, 100, 0, 300, EpipolarGridOptions(), 1).ok());
}
