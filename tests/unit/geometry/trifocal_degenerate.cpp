// Minimum numbers of tracks, and degenerate input: flat terrain, duplicated tracks, non-finite values.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "tpkit/geometry/affine_camera.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/geometry/reproj_eval.hpp"
#include "tpkit/geometry/trifocal_fit.hpp"
#include "tpkit/geometry/trifocal_transfer.hpp"

using namespace tpkit;

namespace {
Eigen::MatrixXd tracks(std::uint64_t seed, int n, double relief = 0.15, double sigma = 0) {
  AffineSceneOptions o;
  o.seed = seed;
  o.relief = relief;
  const AffineScene s = AffineScene::random(o);
  Eigen::MatrixXd xy = s.project(s.points(n, seed + 10));
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> N(0.0, sigma > 0 ? sigma : 1.0);
  if (sigma > 0)
    for (Eigen::Index r = 0; r < xy.rows(); ++r)
      for (int c = 0; c < 6; ++c) xy(r, c) += N(rng);
  return xy;
}
}  // namespace

TEST(MinimumTracks, EachMethodChecksItsMinimum) {
  EXPECT_EQ(trifocal_min_tracks(TrifocalMethod::Dlt), 7);
  EXPECT_EQ(trifocal_min_tracks(TrifocalMethod::ThreeF), 8);
  for (TrifocalMethod m : {TrifocalMethod::AffineDlt, TrifocalMethod::Algebraic, TrifocalMethod::Minimal, TrifocalMethod::Ml})
    EXPECT_EQ(trifocal_min_tracks(m), 4);
  for (TrifocalMethod m : all_trifocal_methods()) {
    const int k = trifocal_min_tracks(m);
    EXPECT_THROW(fit_trifocal(m, tracks(1, k - 1)), InputError) << trifocal_method_name(m);
    // with exactly the minimum, noise-free: the true geometry (reprojection exact)
    const Eigen::MatrixXd xy = tracks(2, k);
    const Eigen::MatrixXd check = tracks(2, 40).bottomRows(30);  // same scene, other points
    const TrifocalTensor T = fit_trifocal(m, xy);
    EXPECT_LT(evaluate_reprojection(reprojection_frame(T, xy), xy).stats.rmse, 1e-6) << trifocal_method_name(m);
    if (m != TrifocalMethod::Dlt) {
      // dlt with 7 tracks of affine views: 28 equations for 26 unknowns, exact on the fit tracks;
      // the others determine the geometry itself
      const Eigen::MatrixXd x3 = transfer_point_line_point(T, check.leftCols(4));
      EXPECT_LT((x3 - check.rightCols(2)).cwiseAbs().maxCoeff(), 1e-6) << trifocal_method_name(m);
    }
  }
}

TEST(Degenerate, FlatTerrainIsRejectedByEveryMethod) {
  for (TrifocalMethod m : all_trifocal_methods()) {
    for (double sigma : {0.0, 0.5}) {
      const Eigen::MatrixXd xy = tracks(3, 100, 0.0, sigma);
      try {
        fit_trifocal(m, xy);
        ADD_FAILURE() << trifocal_method_name(m) << " accepted flat terrain (sigma " << sigma << ")";
      } catch (const NumericalError& e) {
        EXPECT_NE(std::string(e.what()).find("flat terrain"), std::string::npos) << e.what();
      }
    }
  }
}

TEST(Degenerate, DuplicatedTrackIsRejected) {
  Eigen::MatrixXd xy = tracks(4, 20);
  xy.row(13) = xy.row(5);
  for (TrifocalMethod m : all_trifocal_methods()) {
    try {
      fit_trifocal(m, xy);
      ADD_FAILURE() << trifocal_method_name(m);
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("records 6 and 14"), std::string::npos) << e.what();
    }
  }
}

TEST(Degenerate, NonFiniteIsRejected) {
  Eigen::MatrixXd xy = tracks(5, 20);
  xy(3, 4) = std::numeric_limits<double>::quiet_NaN();
  for (TrifocalMethod m : all_trifocal_methods()) EXPECT_THROW(fit_trifocal(m, xy), InputError);
  xy(3, 4) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(fit_trifocal(TrifocalMethod::Ml, xy), InputError);
}

TEST(Degenerate, RansacRejectsFlatInliers) {
  const Eigen::MatrixXd xy = tracks(6, 200, 0.0, 0.5);
  RansacOptions ro;
  EXPECT_THROW(fit_trifocal_ransac(TrifocalMethod::Ml, xy, ro), NumericalError);
}

TEST(Degenerate, TwoViewsOnlyIsAnInputError) {
  EXPECT_THROW(fit_trifocal(TrifocalMethod::Ml, tracks(7, 20).leftCols(4)), InputError);
}
