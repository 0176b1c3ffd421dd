// three-f on single-pass geometry: random satellite-like affine triplets whose three viewing directions
// are coplanar (the camera centres at infinity collinear), where three fundamental matrices do not
// determine the third camera (H&Z 15.4): three-f refuses them, and is exact off that plane. (Its noise
// figures against ml by epipolar angle: bench_trifocal --coplanar.)
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "tpkit/affine_camera.hpp"
#include "tpkit/error.hpp"
#include "tpkit/trifocal_fit.hpp"
#include "tpkit/trifocal_three_f.hpp"
#include "tpkit/trifocal_transfer.hpp"

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

}  // namespace
