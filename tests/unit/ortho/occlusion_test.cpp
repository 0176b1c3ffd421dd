// Hidden ground against closed form: a box on flat ground seen along a known line of sight hides a strip
// behind it as long as its height times the line of sight; its edges are walls; and the line of sight of a
// model whose parallax is known.
#include <gtest/gtest.h>

#include <cmath>

#include "tpkit/ortho/occlusion.hpp"
#include "affine_rpc.hpp"

using namespace tpkit;

namespace {

// 100 x 100 grid pixels from (c0, r0) = (-10, 5): ground at 2 m, a box `top` m high over columns and rows
// [40, 60) of the grid (grid coordinates).
HeightWindow box_window(double top) {
  HeightWindow H{-10, 5, 100, 100, std::vector<double>(100 * 100, 2.0)};
  for (long r = 40; r < 60; ++r)
    for (long c = 40; c < 60; ++c) H.z[static_cast<size_t>((r - H.r0) * H.width + (c - H.c0))] = 2 + top;
  return H;
}

// the hidden columns of grid row r, from the marks of the rectangle (c0, r0, w, h)
std::vector<long> hidden_columns(const std::vector<char>& m, long c0, long r0, long w, long r) {
  std::vector<long> cols;
  for (long c = c0; c < c0 + w; ++c)
    if (m[static_cast<size_t>((r - r0) * w + (c - c0))]) cols.push_back(c);
  return cols;
}

}  // namespace

TEST(Occlusion, BoxHidesAStripAsLongAsItsHeightAlongTheLineOfSight) {
  const HeightWindow H = box_window(10);
  // the sensor towards +c: 0.5 px per metre (10 m: 5 px)
  std::vector<char> m;
  const long n = mark_hidden(H, {0.5, 0}, 0, 20, 80, 70, 0.5, m);
  // ground at column c is hidden when its ray, rising 2 m per px, is still below the roof at the box's edge
  // (the surface ramps from column 39 to 40): from column 36 (8 m short of 10 m at 40) to 39
  for (long r = 40; r < 60; ++r) {
    const std::vector<long> cols = hidden_columns(m, 0, 20, 80, r);
    ASSERT_FALSE(cols.empty()) << "row " << r;
    EXPECT_GE(cols.front(), 35) << "row " << r;
    EXPECT_LE(cols.front(), 36) << "row " << r;
    EXPECT_EQ(cols.back(), 39) << "row " << r;
    EXPECT_EQ(static_cast<long>(cols.size()), cols.back() - cols.front() + 1) << "row " << r;
  }
  // nothing hidden in the rows the box does not reach, on its roof, or on the side facing the sensor
  for (long r : {20L, 39L, 60L, 89L}) EXPECT_TRUE(hidden_columns(m, 0, 20, 80, r).empty()) << "row " << r;
  EXPECT_EQ(n, 20 * static_cast<long>(hidden_columns(m, 0, 20, 80, 50).size()));
}

TEST(Occlusion, TallerBoxLongerStripAndOtherDirections) {
  const HeightWindow H = box_window(20);
  std::vector<char> m;
  // the sensor towards -r (north in a grid whose rows run south): the strip lies south of the box, 10 px
  mark_hidden(H, {0, -0.5}, 0, 20, 80, 70, 0.5, m);
  long south = 0, north = 0;
  for (long r = 20; r < 90; ++r)
    if (m[static_cast<size_t>((r - 20) * 80 + (50 - 0))]) (r >= 60 ? south : north)++;
  EXPECT_EQ(north, 0);
  EXPECT_GE(south, 9);
  EXPECT_LE(south, 10);
  // a vertical view hides nothing
  EXPECT_EQ(mark_hidden(H, {0, 0}, 0, 20, 80, 70, 0.5, m), 0);
}

TEST(Occlusion, ToleranceKeepsLowBumps) {
  // a 30 cm kerb seen at a grazing 5 px per metre (the ray rises 0.2 m per pixel): below the 0.5 m
  // tolerance it hides nothing, above a 0.05 m one the pixel before it
  const HeightWindow H = box_window(0.3);
  std::vector<char> m;
  EXPECT_EQ(mark_hidden(H, {5, 0}, 0, 20, 80, 70, 0.5, m), 0);
  EXPECT_EQ(mark_hidden(H, {5, 0}, 0, 20, 80, 70, 0.05, m), 20);
  EXPECT_EQ(hidden_columns(m, 0, 20, 80, 50), (std::vector<long>{39}));
}

TEST(Occlusion, WallsAreTheBoxEdges) {
  const HeightWindow H = box_window(10);
  std::vector<char> m(80 * 70, 0);
  // 0.5 m pixels: the edge rises 10 m over a pixel, the roof and the ground are flat
  const long n = mark_walls(H, 0.5, 60, 0, 20, 80, 70, m);
  EXPECT_EQ(hidden_columns(m, 0, 20, 80, 50), (std::vector<long>{39, 40, 59, 60}));
  EXPECT_GT(n, 0);
  // 90 degrees: nothing is a wall... and 80 degrees over 50 m pixels: a 10 m step is no wall either
  std::vector<char> k(80 * 70, 0);
  EXPECT_EQ(mark_walls(H, 50, 80, 0, 20, 80, 70, k), 0);
}

TEST(Occlusion, MarginCoversTheReliefAlongTheLineOfSight) {
  EXPECT_EQ(occluder_margin({0.3, 0.4}, 20, 512), 12);   // 0.5 px/m x 20 m + 2
  EXPECT_EQ(occluder_margin({0.3, 0.4}, 5000, 512), 512);
  EXPECT_EQ(occluder_margin({NAN, 0}, 20, 512), 0);
}

TEST(Occlusion, LineOfSightOfAModelWithKnownParallax) {
  // affine_rpc.hpp: one metre higher moves x by 0.1 px, as 1e-6 degree of longitude does; so the ground point
  // seen one metre higher lies 1e-6 degree west
  const RpcModel m = affine_rpc(3.0);  // on the central meridian of UTM zone 31: grid north is true north
  const GridCrs crs(32631);
  double x = 3.0, y = 43.3;
  crs.from_lonlat(1, &x, &y);
  OrthoGrid g;
  g.epsg = 32631;
  g.gsd = 0.5;
  g.x0 = std::floor(x) - 50;
  g.y0 = std::floor(y) + 50;
  g.width = g.height = 200;
  const LineOfSight los = line_of_sight(m, g, crs, 100, 100, 120);
  // 1e-6 deg of longitude at 43.3 N on the WGS 84 ellipsoid (N cos(lat) per radian), times UTM's scale on
  // its central meridian, in 0.5 m grid pixels: 0.1622 px west
  const double phi = 43.3 * M_PI / 180, e2 = 0.00669437999014;
  const double metres = 6378137.0 / std::sqrt(1 - e2 * std::sin(phi) * std::sin(phi)) * std::cos(phi) * 1e-6 * M_PI / 180;
  EXPECT_NEAR(los.dc, -metres * 0.9996 / 0.5, 1e-4);
  EXPECT_NEAR(los.dr, 0, 0.001);
}
