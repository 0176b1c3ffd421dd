// Noise-free ground truth: every method recovers the tensor of random satellite-like affine cameras
// (full-scene 30000 px frames and 1000 px crops): transfer and reprojection errors < 1e-6 px.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "tpkit/geometry/affine_camera.hpp"
#include "tpkit/geometry/camera_recovery.hpp"
#include "tpkit/geometry/reproj_eval.hpp"
#include "tpkit/geometry/trifocal_fit.hpp"
#include "tpkit/geometry/trifocal_minimal.hpp"
#include "tpkit/geometry/trifocal_transfer.hpp"

using namespace tpkit;

namespace {

struct Case {
  double size;
  std::uint64_t seed;
};

double transfer_rmse(const TrifocalTensor& T, const Eigen::MatrixXd& check) {
  Eigen::MatrixXd pairs = check.leftCols(4);
  Eigen::MatrixXd x3 = transfer_point_line_point(T, pairs);
  return std::sqrt((x3 - check.rightCols(2)).rowwise().squaredNorm().mean());
}

}  // namespace

class ExactMethods : public ::testing::TestWithParam<std::tuple<TrifocalMethod, Case>> {};

TEST_P(ExactMethods, NoiseFreeTransferAndReprojection) {
  const TrifocalMethod m = std::get<0>(GetParam());
  const Case c = std::get<1>(GetParam());
  AffineSceneOptions o;
  o.image_size = c.size;
  o.seed = c.seed;
  const AffineScene scene = AffineScene::random(o);
  const Eigen::MatrixXd fit = scene.project(scene.points(50, c.seed + 100));
  const Eigen::MatrixXd check = scene.project(scene.points(200, c.seed + 200));
  const TrifocalTensor T = fit_trifocal(m, fit);
  const double tr = transfer_rmse(T, check);
  const ReprojectionFrame f = reprojection_frame(T, fit);
  const double rp = evaluate_reprojection(f, fit).stats.rmse;
  const double rc = evaluate_reprojection(f, check).stats.rmse;
  EXPECT_LT(tr, 1e-6) << trifocal_method_name(m) << " size " << c.size;
  EXPECT_LT(rp, 1e-6) << trifocal_method_name(m) << " size " << c.size;
  EXPECT_LT(rc, 1e-6) << trifocal_method_name(m) << " size " << c.size;
  // the fitted tensor equals the truth up to scale and sign
  const Vector27 a = trifocal_to_vector(unit_trifocal(T)), b = trifocal_to_vector(unit_trifocal(scene.trifocal()));
  EXPECT_LT(std::min((a - b).norm(), (a + b).norm()), 1e-6) << trifocal_method_name(m);
}

INSTANTIATE_TEST_SUITE_P(AllMethods, ExactMethods,
                         ::testing::Combine(::testing::ValuesIn(all_trifocal_methods()),
                                            ::testing::Values(Case{1000, 1}, Case{1000, 2}, Case{30000, 3},
                                                              Case{30000, 4})));

TEST(TrifocalTensor, AffineZeroPatternMatchesPaperNumbering) {
  // the paper's zero entries t3 t6 t7 t8 t9 t12 t15 t16 t17 t18 t27 under t_{9i+3j+k+1} = T_i(j,k)
  const int zeros[] = {3, 6, 7, 8, 9, 12, 15, 16, 17, 18, 27};
  AffineSceneOptions o;
  const TrifocalTensor T = AffineScene::random(o).trifocal();
  const Vector27 t = trifocal_to_vector(T);
  for (int q = 1; q <= 27; ++q) {
    const bool zero = std::find(std::begin(zeros), std::end(zeros), q) != std::end(zeros);
    if (zero) EXPECT_EQ(t(q - 1), 0.0) << "t" << q;
    else EXPECT_GT(std::fabs(t(q - 1)), 1e-12 * t.norm()) << "t" << q;
    EXPECT_EQ(zero, affine_zero_entry((q - 1) / 9, ((q - 1) / 3) % 3, (q - 1) % 3));
  }
}

TEST(TrifocalTensor, IncidenceHoldsForTrueTensor) {
  AffineSceneOptions o;
  const AffineScene s = AffineScene::random(o);
  const Eigen::MatrixXd xy = s.project(s.points(20, 5));
  const TrifocalTensor T = unit_trifocal(s.trifocal());
  for (Eigen::Index r = 0; r < xy.rows(); ++r) {
    // scale-free check: incidence of normalized points
    Eigen::Vector3d x1 = track_point(xy, r, 0), x2 = track_point(xy, r, 1), x3 = track_point(xy, r, 2);
    const double scale = x1.norm() * x2.norm() * x3.norm();
    EXPECT_LT(trifocal_incidence(T, x1, x2, x3).norm() / scale, 1e-12);
  }
}

TEST(TrifocalTensor, TransformRoundTrip) {
  AffineSceneOptions o;
  const TrifocalTensor T = AffineScene::random(o).trifocal();
  Eigen::Matrix3d H1, H2, H3;
  H1 << 2, 0.1, 3, 0.2, 1.5, -4, 0.001, 0, 1;
  H2 << 0.5, 0, 10, 0, 0.5, 20, 0, 0, 1;
  H3 << 1, 0.3, 0, -0.3, 1, 5, 0, 0.002, 1;
  const TrifocalTensor back = transform_trifocal(transform_trifocal(T, H1, H2, H3), H1.inverse(), H2.inverse(), H3.inverse());
  for (int i = 0; i < 3; ++i) EXPECT_LT((back[i] - T[i]).norm(), 1e-12 * T[i].norm() + 1e-300);
}

TEST(CameraRecovery, CamerasReproduceTensorAndHaveUnitThirdRows) {
  AffineSceneOptions o;
  o.seed = 9;
  const AffineScene s = AffineScene::random(o);
  const Eigen::MatrixXd xy = s.project(s.points(30, 1));
  const auto H = isotropic_normalization(xy, true);
  const TrifocalTensor Tn = unit_trifocal(transform_trifocal(s.trifocal(), H[0], H[1], H[2]));
  const CameraTriplet P = cameras_from_trifocal(Tn);
  for (int v = 0; v < 3; ++v) EXPECT_NEAR(P[v].row(2).norm(), 1.0, 1e-12);
  const Vector27 a = trifocal_to_vector(unit_trifocal(trifocal_from_cameras(P[0], P[1], P[2])));
  const Vector27 b = trifocal_to_vector(Tn);
  EXPECT_LT(std::min((a - b).norm(), (a + b).norm()), 1e-10);
}

TEST(MinimalParameterization, AffineCoreHasTenNonZeros) {
  AffineSceneOptions o;
  o.seed = 4;
  const AffineScene s = AffineScene::random(o);
  const Eigen::MatrixXd xy = s.project(s.points(30, 1));
  // a frame whose origins are not one point's projections (shifted from the centroids)
  auto H = isotropic_normalization(xy, true);
  H[0](0, 2) += 0.3;
  H[2](1, 2) -= 0.2;
  const CameraTriplet P = cameras_from_trifocal(unit_trifocal(transform_trifocal(s.trifocal(), H[0], H[1], H[2])));
  const MinimalParameterization mp = minimal_parameterization(P);
  EXPECT_EQ(mp.nonzero, 10);
  EXPECT_LT(mp.off_pattern, 1e-12);
  for (const auto* M : {&mp.U, &mp.V, &mp.W}) {
    EXPECT_LT((M->transpose() * *M - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_NEAR(M->determinant(), 1.0, 1e-12);
  }
}
