// The alignment of two orthos measured against a shift made on purpose: a texture given in closed form (a
// sum of sines of many frequencies and directions) sampled at x and at x - d, the second with another gain
// and offset (another date), must give d to 0.05 px; on files (two float orthos of one grid) likewise, per
// tile and as the median; orthos of two grids are refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "tpkit/core/error.hpp"
#include "tpkit/ortho/ortho_alignment.hpp"
#include "tpkit/ortho/ortho_geotiff.hpp"

using namespace tpkit;

namespace {

std::string scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("tpkit_ortho_align_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

struct Texture {
  std::vector<double> a, wx, wy, ph;
  explicit Texture(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    for (int k = 0; k < 40; ++k) {
      const double f = 0.05 + 0.6 * u(rng), t = 2 * M_PI * u(rng);
      wx.push_back(f * std::cos(t));
      wy.push_back(f * std::sin(t));
      ph.push_back(2 * M_PI * u(rng));
      a.push_back(10 / (1 + 5 * f));
    }
  }
  double operator()(double x, double y) const {
    double s = 100;
    for (size_t k = 0; k < a.size(); ++k) s += a[k] * std::sin(wx[k] * x + wy[k] * y + ph[k]);
    return s;
  }
};

GreyTile tile_of(const Texture& t, long x0, long y0, long n, double dx, double dy, double gain, double offset) {
  GreyTile g;
  g.width = g.height = n;
  for (long r = 0; r < n; ++r)
    for (long c = 0; c < n; ++c) g.data.push_back(static_cast<float>(gain * t(x0 + c - dx, y0 + r - dy) + offset));
  return g;
}

void write_ortho(const std::string& path, const Texture& t, const OrthoGrid& g, double dx, double dy, double gain) {
  OrthoTiffLayout L;
  L.grid = g;
  L.type = SampleType::f32;
  L.nodata = NAN;
  OrthoTiffWriter w(path, L);
  const long T = OrthoTiffLayout::kTile;
  for (long ty = 0; ty < L.tiles_down(); ++ty)
    for (long tx = 0; tx < L.tiles_across(); ++tx) {
      std::vector<unsigned char> s(static_cast<size_t>(T * T * 4));
      float* f = reinterpret_cast<float*>(s.data());
      for (long r = 0; r < T; ++r)
        for (long c = 0; c < T; ++c) {
          const long x = tx * T + c, y = ty * T + r;
          if (x >= g.width || y >= g.height) continue;  // beyond the grid: padding
          // a nodata band on the left: tiles there are not measured
          f[r * T + c] = x < 100 ? NAN : static_cast<float>(gain * t(x - dx, y - dy));
        }
      w.write_tile(tx, ty, s);
    }
  w.close();
}

}  // namespace

TEST(OrthoAlignment, KnownShiftOfOneTile) {
  const Texture t(7);
  AlignmentOptions o;
  for (const auto& d : std::vector<std::pair<double, double>>{{0.0, 0.0}, {1.3, -0.7}, {-4.25, 2.6}, {0.37, 0.11}}) {
    TileShift s;
    ASSERT_TRUE(measure_tile_shift(tile_of(t, 500, 300, 128, 0, 0, 1, 0), tile_of(t, 500, 300, 128, d.first, d.second, 1.7, -40), o, s));
    EXPECT_NEAR(s.dx, d.first, 0.05);
    EXPECT_NEAR(s.dy, d.second, 0.05);
    EXPECT_GT(s.ecc, 0.9);
  }
}

TEST(OrthoAlignment, FlatTileIsNotMeasured) {
  GreyTile a, b;
  a.width = a.height = b.width = b.height = 64;
  a.data.assign(64 * 64, 5.0f);
  b.data.assign(64 * 64, 5.0f);
  TileShift s;
  EXPECT_FALSE(measure_tile_shift(a, b, AlignmentOptions{}, s));
}

TEST(OrthoAlignment, FilesOfOneGrid) {
  const Texture t(11);
  OrthoGrid g;
  g.epsg = 32617;
  g.x0 = 434000;
  g.y0 = 3355000;
  g.gsd = 0.3;
  g.width = 600;
  g.height = 520;
  const std::string a = scratch("a.tif"), b = scratch("b.tif");
  write_ortho(a, t, g, 0, 0, 1);
  write_ortho(b, t, g, 2.4, -1.15, 0.6);
  AlignmentOptions o;
  o.threads = 2;
  const PairAlignment p = measure_alignment(a, b, o);
  // 4 x 4 tiles of 128 centred on the grid: those reaching into the nodata band (x < 100) are not tried
  EXPECT_EQ(p.tiles_tried, 12);
  EXPECT_EQ(p.tiles.size(), 12u);
  EXPECT_NEAR(p.dx, 2.4, 0.05);
  EXPECT_NEAR(p.dy, -1.15, 0.05);
  EXPECT_LT(p.nmad_dx, 0.05);
  EXPECT_LT(p.nmad_dy, 0.05);
  // another grid: refused
  OrthoGrid g2 = g;
  g2.x0 += 0.3;
  const std::string c = scratch("c.tif");
  write_ortho(c, t, g2, 0, 0, 1);
  EXPECT_THROW(measure_alignment(a, c, o), InputError);
}
