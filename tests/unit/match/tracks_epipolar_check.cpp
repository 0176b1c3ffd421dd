// tp-chain --rpc-check (tracks_epipolar_check.hpp) against truth: five affine views of a ground volume
// from different directions, their RPC models fitted to the cameras and then biased (shifted by up to
// 12 px, as delivered models are), tracks projected from truth ground points with 0.1 px of noise, and
// in a fifth of the tracks of three views or more one view moved 3 px off (a wrong match). The wrong
// views go, the good ones stay, the pairs' biases are measured; a wrong pair of two views goes whole.
#include "tpkit/match/tracks_epipolar_check.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <cmath>
#include <random>

using namespace tpkit;

namespace {

constexpr double kLat = 30.3, kLon = -81.7, kGround = 0;
constexpr int kViews = 5;

// View v's affine camera of local ENU metres: pixels (x column, y row), 0.5 m pixels, parallax of
// 0.2-0.5 px per metre of height in a direction of its own.
Eigen::Vector2d camera(int v, double E, double N, double U) {
  const double az = 2 * M_PI * v / kViews + 0.3, k = 0.2 + 0.075 * v;
  return {E / 0.5 + 500 + k * std::cos(az) * U / 0.5, -N / 0.5 + 500 + k * std::sin(az) * U / 0.5};
}

struct Scene {
  RpcModel model[kViews];
  Eigen::Vector2d bias[kViews];
};

const Scene& scene() {
  static const Scene s = [] {
    Scene sc;
    const GeographicLib::LocalCartesian lc(kLat, kLon, kGround);
    RpcFitVolume vol;
    double lat, lon, h;
    lc.Reverse(-300, -300, 0, lat, lon, h);
    vol.lat0 = lat, vol.lon0 = lon;
    lc.Reverse(300, 300, 0, lat, lon, h);
    vol.lat1 = lat, vol.lon1 = lon;
    vol.h0 = kGround - 50, vol.h1 = kGround + 50;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> B(-12, 12);
    for (int v = 0; v < kViews; ++v) {
      sc.model[v] = fit_rpc([&](const Eigen::Vector3d& llh) {
        double E, N, U;
        lc.Forward(llh[1], llh[0], llh[2], E, N, U);
        return camera(v, E, N, llh[2] - kGround);
      }, vol).model;
      // the delivered model's bias: it puts every point this far from where the image sees it
      sc.bias[v] = v == 0 ? Eigen::Vector2d(0, 0) : Eigen::Vector2d(B(rng), B(rng));
      sc.model[v].samp_off += sc.bias[v].x();
      sc.model[v].line_off += sc.bias[v].y();
    }
    return sc;
  }();
  return s;
}

}  // namespace

TEST(TracksEpipolarCheck, DropsTheViewsTheModelsContradict) {
  const Scene& s = scene();
  const int P = 1500;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-250, 250), H(-30, 30), Uni(0, 1);
  std::normal_distribution<double> noise(0, 0.1);
  Tracks t;
  for (int v = 0; v < kViews; ++v) t.images.push_back({"v" + std::to_string(v + 1), 1000, 1000});
  t.xy.resize(P, 2 * kViews);
  std::vector<int> wrong(P, -1);
  std::vector<std::vector<int>> sees(P);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int p = 0; p < P; ++p) {
    const double E = U(rng), N = U(rng), Z = H(rng);
    for (int v = 0; v < kViews; ++v) {
      if (Uni(rng) < 0.45) {
        t.xy(p, 2 * v) = t.xy(p, 2 * v + 1) = nan;
        continue;
      }
      sees[p].push_back(v);
      const Eigen::Vector2d x = camera(v, E, N, Z) + Eigen::Vector2d(noise(rng), noise(rng));
      t.xy(p, 2 * v) = x.x(), t.xy(p, 2 * v + 1) = x.y();
    }
    if (sees[p].size() < 2) {  // at least two views
      for (int v : {0, 1})
        if (std::isnan(t.xy(p, 2 * v))) {
          const Eigen::Vector2d x = camera(v, E, N, Z);
          t.xy(p, 2 * v) = x.x(), t.xy(p, 2 * v + 1) = x.y();
          sees[p].push_back(v);
        }
      std::sort(sees[p].begin(), sees[p].end());
      sees[p].erase(std::unique(sees[p].begin(), sees[p].end()), sees[p].end());
    }
    if (Uni(rng) < 0.2) {  // a wrong view: 3 px off in a random direction
      const int w = sees[p][rng() % sees[p].size()];
      const double a = 2 * M_PI * Uni(rng);
      t.xy(p, 2 * w) += 3 * std::cos(a), t.xy(p, 2 * w + 1) += 3 * std::sin(a);
      wrong[p] = w;
    }
    t.id.push_back(p);
  }
  const Tracks before = t;
  std::vector<const RpcModel*> models;
  for (const auto& m : s.model) models.push_back(&m);
  EpipolarCheckOptions o;
  o.threshold = 1.0;
  o.threads = 2;
  const EpipolarCheckStats st = epipolar_check(t, models, o);
  EXPECT_EQ(st.pairs_judged, kViews * (kViews - 1) / 2);
  EXPECT_LT(st.median_sigma, 0.3);
  EXPECT_GT(st.largest_bias, 5);  // the models' biases are measured, not taken for wrong matches
  // match the tracks kept back to the truth by their positions in a view they keep
  long wrong_long = 0, wrong_long_dropped = 0, good_views = 0, good_lost = 0, kept = 0;
  size_t r = 0;
  for (int p = 0; p < P; ++p) {
    const bool long_track = sees[p].size() >= 3;
    // is track p still there? the kept tracks keep their order
    bool present = false;
    if (r < t.size()) {
      present = true;
      for (int v = 0; v < kViews && present; ++v)
        if (t.seen(r, v)) present = t.point(r, v) == before.point(static_cast<size_t>(p), v);
      if (t.seen_views(r) == 0) present = false;
    }
    if (long_track && wrong[p] >= 0) {
      ++wrong_long;
      // with three views or more the wrong one goes, unless its 3 px lie along its partners' curves
      // (a three-view track whose wrong view only one partner contradicts: a tie, the later view goes)
      if (present && !t.seen(r, wrong[p])) ++wrong_long_dropped;
    }
    for (int v : sees[p]) {
      if (v == wrong[p]) continue;
      ++good_views;
      if (!present || !t.seen(r, v)) ++good_lost;
    }
    if (present) ++r, ++kept;
  }
  EXPECT_EQ(r, t.size());  // every kept track matched
  ASSERT_GT(wrong_long, 100);
  EXPECT_GE(wrong_long_dropped, 0.85 * static_cast<double>(wrong_long)) << wrong_long_dropped << " of " << wrong_long;
  // good views lost: those of the two-view tracks whose partner was wrong (both go), and hardly more
  long two_view_wrong = 0;
  for (int p = 0; p < P; ++p) two_view_wrong += sees[p].size() == 2 && wrong[p] >= 0;
  EXPECT_LE(good_lost, two_view_wrong + 0.01 * static_cast<double>(good_views)) << good_lost << " of " << good_views;
  EXPECT_EQ(static_cast<size_t>(kept), t.size());
  for (size_t k = 0; k < t.size(); ++k) EXPECT_EQ(t.id[k], static_cast<long long>(k));
}
