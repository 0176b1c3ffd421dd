// Accuracy under noise against ground truth (random satellite-like affine triplets, sigma = 0.5 px),
// the ML-bound goals with a reduced number of trials, and the robust-fitting goals.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <random>

#include "tpkit/geometry/affine_camera.hpp"
#include "tpkit/geometry/camera_recovery.hpp"
#include "tpkit/geometry/reproj_eval.hpp"
#include "tpkit/geometry/trifocal_affine_dlt.hpp"
#include "tpkit/geometry/trifocal_dlt.hpp"
#include "tpkit/geometry/trifocal_fit.hpp"
#include "tpkit/geometry/trifocal_ml.hpp"
#include "tpkit/geometry/trifocal_transfer.hpp"

using namespace tpkit;

namespace {

constexpr double kSigma = 0.5;

struct Data {
  AffineScene scene;
  Eigen::MatrixXd fit, truth, check;
};

Data make(std::uint64_t seed, int n, double size = 1000) {
  AffineSceneOptions o;
  o.seed = seed;
  o.image_size = size;
  Data d{AffineScene::random(o), {}, {}, {}};
  d.truth = d.scene.project(d.scene.points(n, seed * 1000 + 1));
  d.check = d.scene.project(d.scene.points(500, seed * 1000 + 2));
  std::mt19937_64 rng(seed * 1000 + 3);
  std::normal_distribution<double> N(0.0, kSigma);
  d.fit = d.truth;
  for (Eigen::Index r = 0; r < d.fit.rows(); ++r)
    for (int c = 0; c < 6; ++c) d.fit(r, c) += N(rng);
  return d;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

double fit_rmse(const TrifocalTensor& T, const Eigen::MatrixXd& xy) {
  return evaluate_reprojection(reprojection_frame(T, xy), xy).stats.rmse;
}

double transfer_rmse(const TrifocalTensor& T, const Eigen::MatrixXd& check) {
  const Eigen::MatrixXd x3 = transfer_point_line_point(T, check.leftCols(4));
  return std::sqrt((x3 - check.rightCols(2)).rowwise().squaredNorm().mean());
}

// median over trials of (per-coordinate fit RMSE) / (ML bound sigma sqrt((n-4)/(2n)))
struct Figures {
  double ratio, transfer;
};
Figures figures(TrifocalMethod m, int n, int trials) {
  std::vector<double> r, t;
  for (int k = 1; k <= trials; ++k) {
    const Data d = make(static_cast<std::uint64_t>(k), n);
    const TrifocalTensor T = fit_trifocal(m, d.fit);
    r.push_back(fit_rmse(T, d.fit) / std::sqrt(2.0) / (kSigma * std::sqrt((n - 4.0) / (2.0 * n))));
    t.push_back(transfer_rmse(T, d.check));
  }
  return {median(r), median(t)};
}

std::vector<char> add_outliers(Eigen::MatrixXd& xy, double share, double size, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<char> out(xy.rows(), 0);
  for (Eigen::Index r = 0; r < xy.rows(); ++r)
    if (U(rng) < share) {
      out[r] = 1;
      const int v = static_cast<int>(U(rng) * 3) % 3;
      double nx, ny;
      do {
        nx = U(rng) * size;
        ny = U(rng) * size;
      } while (std::hypot(nx - xy(r, 2 * v), ny - xy(r, 2 * v + 1)) < 20);
      xy(r, 2 * v) = nx;
      xy(r, 2 * v + 1) = ny;
    }
  return out;
}

}  // namespace

// Goals of issue 4 (ml within 2% of the bound, the affine methods within 5%) with 25 trials at n = 100.
// A wrong method (wrong zero pattern, unnormalized data, a bad camera recovery) is far off these.
TEST(NoiseGoals, AffineMethodsNearMlBound) {
  const struct {
    TrifocalMethod m;
    double max_ratio;
  } goals[] = {{TrifocalMethod::Ml, 1.02},
               {TrifocalMethod::AffineDlt, 1.05},
               {TrifocalMethod::Algebraic, 1.05},
               {TrifocalMethod::Minimal, 1.05},
               {TrifocalMethod::ThreeF, 1.05}};
  for (const auto& g : goals) {
    const Figures f = figures(g.m, 100, 25);
    EXPECT_LE(f.ratio, g.max_ratio) << trifocal_method_name(g.m);
    EXPECT_GT(f.ratio, 0.9) << trifocal_method_name(g.m);  // not below what the ML fit can reach
    EXPECT_LT(f.transfer, 0.6) << trifocal_method_name(g.m);
  }
}

TEST(NoiseGoals, MlSmallAndLargeN) {
  for (int n : {10, 1000}) {
    const Figures f = figures(TrifocalMethod::Ml, n, 15);
    EXPECT_LE(f.ratio, 1.02) << n;
    EXPECT_GT(f.ratio, 0.9) << n;
  }
}

// The general DLT with its constraint step: <= 1.3x the bound at every n (issue 4). With 10 tracks the
// projective model (18 degrees of freedom against the affine 12) may fit below the affine bound, but
// never below the projective one, sigma sqrt((n - 6) / (2n)) = 0.82x of it at n = 10.
TEST(NoiseGoals, DltWithinGoal) {
  for (int n : {10, 100, 1000}) {
    const Figures f = figures(TrifocalMethod::Dlt, n, n == 1000 ? 5 : 25);
    EXPECT_LE(f.ratio, 1.3) << n;
    EXPECT_GT(f.ratio, n == 10 ? 0.75 : 0.95) << n;
  }
}

// Without the constraint step the linear tensor is not the tensor of any three cameras, and the
// cameras recovered from it fit the tracks far worse (3.9x the bound at n = 10 in the benchmark).
TEST(NoiseGoals, DltConstraintStepMatters) {
  double raw = 0, constrained = 0;
  for (std::uint64_t seed = 1; seed <= 9; ++seed) {
    const Data d = make(seed, 10);
    raw += fit_rmse(trifocal_dlt(d.fit, false), d.fit);
    constrained += fit_rmse(trifocal_dlt(d.fit), d.fit);
  }
  EXPECT_GT(raw, 2.0 * constrained);
}

// The constrained DLT tensor is geometrically valid on noisy tracks: the cameras recovered from it
// reproduce it.
TEST(NoiseGoals, DltTensorIsGeometricallyValid) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const Data d = make(seed, 30, seed == 3 ? 30000 : 1000);
    const auto H = isotropic_normalization(d.fit, false);
    const TrifocalTensor T = unit_trifocal(transform_trifocal(trifocal_dlt(d.fit), H[0], H[1], H[2]));
    const CameraTriplet P = cameras_from_trifocal(T);
    const Vector27 a = trifocal_to_vector(unit_trifocal(trifocal_from_cameras(P[0], P[1], P[2])));
    const Vector27 b = trifocal_to_vector(T);
    EXPECT_LT(std::min((a - b).norm(), (a + b).norm()), 1e-8) << seed;
  }
}

// reproj-eval's camera recovery + DLT triangulation, applied to the ml tensor, gives the residuals of
// the affine ML fit itself (the three recovered cameras share their third row, the plane at infinity).
TEST(MlConsistency, TriangulationResidualsEqualAffineMlResiduals) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const Data d = make(seed, 200, seed == 3 ? 30000 : 1000);
    const AffineTrifocalFit fit = trifocal_ml(d.fit);
    Eigen::MatrixXd ml_res(d.fit.rows(), 6);
    for (Eigen::Index r = 0; r < d.fit.rows(); ++r)
      for (int v = 0; v < 3; ++v)
        ml_res.block<1, 2>(r, 2 * v) =
            (project(fit.P[v], fit.X.row(r).transpose()) - d.fit.block<1, 2>(r, 2 * v).transpose()).transpose();
    const ReprojectionResult ev = evaluate_reprojection(reprojection_frame(fit.T, d.fit), d.fit);
    const double bound2d = kSigma * std::sqrt((200 - 4.0) / 200.0);
    const double ml_rmse = std::sqrt(ml_res.rowwise().squaredNorm().sum() / (3.0 * d.fit.rows()));
    EXPECT_LT(std::fabs(ev.stats.rmse - ml_rmse), 0.02 * bound2d) << seed;
    EXPECT_LT((ev.residual - ml_res).cwiseAbs().maxCoeff(), 0.02 * bound2d) << seed;
  }
}

// The affine linear solution already satisfies the three internal constraints of an affine tensor
// (each 2x2 block a_i' b4'^T - a4' b_i'^T): cameras recovered from it reproduce it. This is why the
// algebraic method (which enforces them) returns the affine-dlt tensor on affine data.
TEST(MlConsistency, AffineDltTensorIsGeometricallyValid) {
  const Data d = make(4, 50);
  const auto H = isotropic_normalization(d.fit, false);
  const TrifocalTensor T = unit_trifocal(transform_trifocal(trifocal_affine_dlt(d.fit), H[0], H[1], H[2]));
  const CameraTriplet P = cameras_from_trifocal(T);
  const Vector27 a = trifocal_to_vector(unit_trifocal(trifocal_from_cameras(P[0], P[1], P[2])));
  const Vector27 b = trifocal_to_vector(T);
  EXPECT_LT(std::min((a - b).norm(), (a + b).norm()), 1e-9);
  const Vector27 c = trifocal_to_vector(fit_trifocal(TrifocalMethod::Algebraic, d.fit));
  const Vector27 e = trifocal_to_vector(fit_trifocal(TrifocalMethod::AffineDlt, d.fit));
  EXPECT_LT(std::min((c - e).norm(), (c + e).norm()), 1e-8);
}

// 30% gross outliers, --ransac 1.5: >= 99% of the true inliers kept, RMSE on them within 5% of the fit
// without outliers.
TEST(Ransac, ThirtyPercentOutliers) {
  for (TrifocalMethod m : {TrifocalMethod::Ml, TrifocalMethod::AffineDlt, TrifocalMethod::Minimal, TrifocalMethod::Dlt,
                           TrifocalMethod::ThreeF, TrifocalMethod::Algebraic}) {
    for (std::uint64_t seed : {1, 2}) {
      Data d = make(seed, 1000);
      Eigen::MatrixXd dirty = d.fit;
      const std::vector<char> out = add_outliers(dirty, 0.3, 1000, seed + 50);
      RansacOptions ro;
      ro.threshold = 1.5;
      ro.seed = seed;
      const RobustTrifocalFit rf = fit_trifocal_ransac(m, dirty, ro);
      std::vector<Eigen::Index> idx;
      long kept = 0, false_in = 0;
      for (Eigen::Index r = 0; r < dirty.rows(); ++r) {
        if (!out[r]) {
          idx.push_back(r);
          kept += rf.inlier[r];
        } else {
          false_in += rf.inlier[r];
        }
      }
      Eigen::MatrixXd clean(idx.size(), 6);
      for (size_t q = 0; q < idx.size(); ++q) clean.row(q) = d.fit.row(idx[q]);
      EXPECT_GE(static_cast<double>(kept) / idx.size(), 0.99) << trifocal_method_name(m);
      EXPECT_LT(false_in, 0.02 * (dirty.rows() - idx.size())) << trifocal_method_name(m);
      const double ref = fit_rmse(fit_trifocal(m, clean), clean);
      EXPECT_LE(fit_rmse(rf.T, clean), 1.05 * ref) << trifocal_method_name(m);
    }
  }
}

TEST(Ransac, SameSeedSameResult) {
  Data d = make(7, 300);
  add_outliers(d.fit, 0.3, 1000, 3);
  RansacOptions ro;
  ro.seed = 11;
  const RobustTrifocalFit a = fit_trifocal_ransac(TrifocalMethod::Ml, d.fit, ro);
  const RobustTrifocalFit b = fit_trifocal_ransac(TrifocalMethod::Ml, d.fit, ro);
  EXPECT_EQ(a.inlier, b.inlier);
  EXPECT_EQ(trifocal_to_vector(a.T), trifocal_to_vector(b.T));
}

TEST(Transfer, NoisyPairsAreCorrectedOntoTheEpipolarGeometry) {
  // transfer of noisy pairs with the true tensor: error of the order of the noise, never wild
  const Data d = make(5, 10);
  const TrifocalTensor T = d.scene.trifocal();
  Eigen::MatrixXd pairs = d.check.leftCols(4);
  std::mt19937_64 rng(9);
  std::normal_distribution<double> N(0.0, kSigma);
  for (Eigen::Index r = 0; r < pairs.rows(); ++r)
    for (int c = 0; c < 4; ++c) pairs(r, c) += N(rng);
  const Eigen::MatrixXd x3 = transfer_point_line_point(T, pairs);
  const double rmse = std::sqrt((x3 - d.check.rightCols(2)).rowwise().squaredNorm().mean());
  EXPECT_LT(rmse, 4 * kSigma);
  EXPECT_GT(rmse, 0.1 * kSigma);
}

// minimal optimizes the reprojection error over exactly the affine tensors, so it must land on the ML
// (Tomasi-Kanade) solution, starting from the different affine-dlt tensor.
TEST(MlConsistency, MinimalConvergesToMl) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const Data d = make(seed, 60);
    const TrifocalTensor Tm = fit_trifocal(TrifocalMethod::Minimal, d.fit);
    const TrifocalTensor Tl = fit_trifocal(TrifocalMethod::Ml, d.fit);
    const TrifocalTensor Ta = fit_trifocal(TrifocalMethod::AffineDlt, d.fit);
    const Eigen::MatrixXd pm = transfer_point_line_point(Tm, d.check.leftCols(4));
    const Eigen::MatrixXd pl = transfer_point_line_point(Tl, d.check.leftCols(4));
    const Eigen::MatrixXd pa = transfer_point_line_point(Ta, d.check.leftCols(4));
    EXPECT_LT((pm - pl).cwiseAbs().maxCoeff(), 1e-4) << seed;
    EXPECT_GT((pa - pl).cwiseAbs().maxCoeff(), 1e-3) << seed;  // the start was elsewhere
  }
}
