// The size of a pair's LSM window (window_size.hpp): the ratio of the differences along and across the
// epipolar lines, and the search over the candidates on a simulated sample whose errors per size are
// known: isotropic noise that shrinks with the window, and a bias along the epipolar lines where the
// affine window is too large for the terrain.
#include "tpkit/match/window_size.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

using namespace tpkit;

namespace {

// Conventions of the simulation: image 2's epipolar lines run along u = (0.8, 0.6); a record's true
// position is x2 = A x1 + t + parallax along u; each size adds its own Gaussian noise (`noise` px in
// both directions) and, for a biased size, a bias along u of `bias` px times a standard normal (the
// terrain's curvature differs from record to record).
struct SizeErrors {
  double noise, bias;
};
const Eigen::Vector2d kU(0.8, 0.6);

WindowSizeSample simulate(const SizeErrors& e, int n, unsigned seed) {
  std::mt19937 truth_rng(7), rng(seed);
  std::uniform_real_distribution<double> pos(0, 1000), par(-10, 10);
  std::normal_distribution<double> g(0, 1);
  const Eigen::Vector2d nrm(-kU.y(), kU.x());
  WindowSizeSample s;
  s.xy.resize(n, 4);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2d p(pos(truth_rng), pos(truth_rng));
    const Eigen::Vector2d q = Eigen::Vector2d(0.97 * p.x() + 0.05 * p.y() + 12, -0.04 * p.x() + 1.02 * p.y() - 7) + par(truth_rng) * kU;
    const Eigen::Vector2d err = e.noise * (g(rng) * kU + g(rng) * nrm) + e.bias * g(rng) * kU;
    s.xy.row(k) << p.x(), p.y(), q.x() + err.x(), q.y() + err.y();
    s.ok.push_back(1);
  }
  return s;
}

// The refinement the search calls: each size and model its own errors (a size not in the table fails).
std::function<WindowSizeSample(const WindowSize&)> sizes(const std::map<std::pair<double, bool>, SizeErrors>& table, int n = 1000) {
  return [table, n](const WindowSize& w) {
    const auto it = table.find({w.taper, w.quadratic});
    if (it == table.end()) {
      WindowSizeSample none = simulate({1, 0}, n, 1);
      std::fill(none.ok.begin(), none.ok.end(), 0);
      return none;
    }
    return simulate(it->second, n, static_cast<unsigned>(100 * w.taper + (w.quadratic ? 1 : 0)));
  };
}

}  // namespace

TEST(WindowSize, RatioAlongAcross) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0, 1);
  std::vector<Eigen::Vector2d> d;
  for (int k = 0; k < 4000; ++k) d.emplace_back(2 * g(rng), 0.5 * g(rng));  // along x twice, across y half
  EXPECT_NEAR(along_across_ratio(d, {1, 0}), 4.0, 0.2);
  EXPECT_NEAR(along_across_ratio(d, {0, 3}), 0.25, 0.02);  // the direction's length does not matter
  EXPECT_TRUE(std::isnan(along_across_ratio({{1, 0}, {2, 0}}, {1, 0})));  // too few
  EXPECT_TRUE(std::isnan(along_across_ratio(d, {0, 0})));                 // no direction
}

// Isotropic noise that falls with the window and no bias: the largest size is taken, affine.
TEST(WindowSize, UnbiasedLargerWindowsAreKept) {
  const WindowSizeChoice c = choose_window_size(sizes({{{3, false}, {0.10, 0}}, {{5, false}, {0.06, 0}}, {{7, false}, {0.045, 0}}}),
                                                {3, 21, false}, window_size_candidates(), kU);
  EXPECT_EQ(c.size.taper, 7);
  EXPECT_EQ(c.size.window, 39);
  EXPECT_FALSE(c.size.quadratic);
  ASSERT_EQ(c.tried.size(), 2u);  // each size's affine model kept: its quadratic one not tried
  for (const auto& t : c.tried) {
    EXPECT_TRUE(t.kept);
    EXPECT_NEAR(t.ratio, 1.0, 0.15);
    EXPECT_LT(t.spread, t.spread_before);
  }
}

// Terrain that curves within the larger windows: the affine window's bias along the epipolar lines
// shows in the differences from the base and it is refused; the quadratic model of the same size, without
// the bias, is kept; at taper 7 px both carry a bias and the search stops at taper 5.
TEST(WindowSize, BiasAlongTheEpipolarLinesIsRefused) {
  const WindowSizeChoice c =
      choose_window_size(sizes({{{3, false}, {0.10, 0}}, {{5, false}, {0.06, 0.15}}, {{5, true}, {0.07, 0}},
                                {{7, false}, {0.045, 0.3}}, {{7, true}, {0.05, 0.2}}}),
                         {3, 21, false}, window_size_candidates(), kU);
  EXPECT_EQ(c.size.taper, 5);
  EXPECT_TRUE(c.size.quadratic);
  ASSERT_EQ(c.tried.size(), 4u);
  EXPECT_FALSE(c.tried[0].kept);
  EXPECT_GT(c.tried[0].ratio, 1.5);
  EXPECT_TRUE(c.tried[1].kept);
  EXPECT_FALSE(c.tried[2].kept);
  EXPECT_FALSE(c.tried[3].kept);
  // a window no better than the base (the texture is what limits it) is not taken either
  const WindowSizeChoice same = choose_window_size(sizes({{{3, false}, {0.10, 0}}, {{5, false}, {0.10, 0}}, {{5, true}, {0.11, 0}}}),
                                                   {3, 21, false}, window_size_candidates(), kU);
  EXPECT_EQ(same.size.taper, 3);
  EXPECT_EQ(same.tried.size(), 2u);
}

// A size whose refinements all fail measures nothing: refused, and the base kept.
TEST(WindowSize, FailedRefinementsKeepTheBase) {
  const WindowSizeChoice c = choose_window_size(sizes({{{3, false}, {0.10, 0}}}), {3, 21, false}, window_size_candidates(), kU);
  EXPECT_EQ(c.size.taper, 3);
  ASSERT_EQ(c.tried.size(), 2u);
  EXPECT_EQ(c.tried[0].common, 0);
  EXPECT_FALSE(c.tried[0].kept);
  const std::string d = describe_window_size(c, false, "");
  EXPECT_NE(d.find("taper 3 px, window 21 px, affine (estimated on 0 sampled matches; taper 5 px affine"), std::string::npos) << d;
  EXPECT_NE(d.find("refused"), std::string::npos);
  EXPECT_EQ(describe_window_size(c, true, ""), "taper 3 px, window 21 px, affine (--window/--taper)");
}
