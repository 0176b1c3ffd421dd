// three-f on single-pass geometry: random satellite-like affine triplets whose three viewing directions
// are coplanar (the camera centres at infinity collinear), where three fundamental matrices do not
// determine the third camera (H&Z 15.4): three-f refuses them, and is exact off that plane. With noise
// (issue 15 section 5): three-f is within 1.5 times ml's transfer error or refused, at 100 and 1000
// tracks. (Its noise figures against ml by epipolar angle: bench_trifocal --coplanar.)
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "tpkit/geometry/affine_camera.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/geometry/trifocal_fit.hpp"
#include "tpkit/geometry/trifocal_three_f.hpp"
#include "tpkit/geometry/trifocal_transfer.hpp"

using namespace tpkit;

namespace {

AffineScene coplanar_scene(std::uint64_t seed, double size, double cross, double spread) {
  AffineSceneOptions o;
  o.seed = seed;
  o.image_size = size;
  return AffineScene::single_pass(o, cross, spread);
}

double transfer_rmse(const TrifocalTensor& T, const Eigen::MatrixXd& check) {
  const Eigen::MatrixXd x3 = transfer_point_line_point(T, check.leftCols(4));
  return std::sqrt((x3 - check.rightCols(2)).rowwise().squaredNorm().mean());
}

constexpr double kDeg = 3.14159265358979323846 / 180;

// n fit tracks with Gaussian noise sigma px per coordinate, 1000 noise-free check tracks
struct Noisy {
  Eigen::MatrixXd fit, check;
};
Noisy noisy(const AffineScene& s, std::uint64_t seed, int n, double sigma) {
  Noisy d{s.project(s.points(n, seed * 1000 + 1)), s.project(s.points(1000, seed * 1000 + 2))};
  std::mt19937_64 rng(seed * 1000 + 3);
  std::normal_distribution<double> N(0.0, sigma);
  for (Eigen::Index r = 0; r < d.fit.rows(); ++r)
    for (int c = 0; c < 6; ++c) d.fit(r, c) += N(rng);
  return d;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

struct RatioFigures {
  std::vector<double> ratio;  // three-f / ml transfer RMSE of the fits three-f accepted
  int refused = 0;
};
template <class SceneOf>
RatioFigures three_f_against_ml(SceneOf scene_of, int n, int trials) {
  RatioFigures f;
  for (int t = 1; t <= trials; ++t) {
    const auto seed = static_cast<std::uint64_t>(t);
    const Noisy d = noisy(scene_of(seed), seed, n, 0.5);
    const double ml = transfer_rmse(fit_trifocal(TrifocalMethod::Ml, d.fit), d.check);
    try {
      f.ratio.push_back(transfer_rmse(fit_trifocal(TrifocalMethod::ThreeF, d.fit), d.check) / ml);
    } catch (const NumericalError& e) {
      EXPECT_NE(std::string(e.what()).find("collinear"), std::string::npos) << e.what();
      ++f.refused;
    }
  }
  return f;
}

TEST(TrifocalThreeFCoplanar, RefusedOnCoplanarDirections) {
  // noise-free: before the check three-f returned tensors 7 to 19 px off here
  for (std::uint64_t seed : {1, 2, 3}) {
    const AffineScene s = coplanar_scene(seed, 1000, 2.5 * kDeg, 0);
    const Eigen::MatrixXd fit = s.project(s.points(200, seed * 1000 + 1));
    try {
      fit_trifocal(TrifocalMethod::ThreeF, fit);
      ADD_FAILURE() << "seed " << seed << ": coplanar directions not refused";
    } catch (const NumericalError& e) {
      EXPECT_NE(std::string(e.what()).find("collinear"), std::string::npos) << e.what();
    }
    // the affine methods are not affected
    const Eigen::MatrixXd check = s.project(s.points(200, seed * 1000 + 2));
    EXPECT_LT(transfer_rmse(fit_trifocal(TrifocalMethod::Ml, fit), check), 1e-6);
  }
}

TEST(TrifocalThreeFCoplanar, ExactOffThePlane) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const AffineScene s = coplanar_scene(seed, 1000, 0, 3 * kDeg);
    const Eigen::MatrixXd fit = s.project(s.points(200, seed * 1000 + 1));
    const Eigen::MatrixXd check = s.project(s.points(200, seed * 1000 + 2));
    ThreeFReport rep;
    const TrifocalTensor T = trifocal_three_f(fit, kThreeFMinAngleDeg, &rep);
    EXPECT_GT(rep.epipolar_angle_deg, kThreeFMinAngleDeg);
    EXPECT_LT(transfer_rmse(T, check), 1e-6) << "seed " << seed << ", angle " << rep.epipolar_angle_deg << " deg";
  }
}

// Exactly coplanar directions, sigma 0.5 px: before the fix (adjustment linearized at the raw
// observations, no third compatibility condition) three-f's transfer error was 2.4 times ml's at 1000
// tracks; now within 1.5 times (the noise keeps the measured angle above 0.05 deg: few refusals).
TEST(TrifocalThreeFCoplanar, NoisyWithinOneAndAHalfOfMlOrRefused) {
  for (int n : {100, 1000}) {
    const RatioFigures f = three_f_against_ml([](std::uint64_t seed) { return coplanar_scene(seed, 1000, 0, 0); }, n, 25);
    ASSERT_GE(f.ratio.size(), 20u) << n << " tracks: " << f.refused << " of 25 refused";
    EXPECT_LE(median(f.ratio), 1.5) << n << " tracks, " << f.refused << " refused";
  }
}

// Off the plane (tp-synth-like triplets, 2-3 deg cross-track; single-pass triplets with 10 deg spread):
// three-f within 1.5 times ml at 1000 tracks and seldom refused. Before the fix: 1.58 and 1.84 times.
TEST(TrifocalThreeFCoplanar, NoisyOffThePlaneWithinOneAndAHalfOfMl) {
  const RatioFigures a = three_f_against_ml(
      [](std::uint64_t seed) {
        AffineSceneOptions o;
        o.seed = seed;
        return AffineScene::random(o);
      },
      1000, 12);
  ASSERT_GE(a.ratio.size(), 9u) << a.refused << " of 12 refused";
  EXPECT_LE(median(a.ratio), 1.35);
  const RatioFigures b = three_f_against_ml([](std::uint64_t seed) { return coplanar_scene(seed, 1000, 0, 10 * kDeg); }, 1000, 12);
  ASSERT_GE(b.ratio.size(), 9u) << b.refused << " of 12 refused";
  EXPECT_LE(median(b.ratio), 1.5);
}

TEST(TrifocalThreeFCoplanar, RefusalThresholdReported) {
  const AffineScene s = coplanar_scene(1, 1000, 0, 10 * kDeg);
  ThreeFReport rep;
  trifocal_three_f(s.project(s.points(400, 5)), kThreeFMinAngleDeg, &rep);
  EXPECT_EQ(rep.min_angle_deg, kThreeFMinAngleDeg);
  EXPECT_GT(rep.epipolar_angle_deg, kThreeFMinAngleDeg);
}

}  // namespace
