// The physical model of section 4 against the paper's eq. 4, and the H -> parameters fit.
#include "tpkit/cluster/physical_homography.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

using namespace tpkit;

TEST(PhysicalHomography, ReproducesEq4WithP2PlusHundred) {
  // Section 5 values with P2 = (100, +100) m (the printed (100, -100) is taken as a sign typo).
  Eigen::Matrix3d H = physical_homography(paper_physical_params());
  Eigen::Matrix3d E = paper_eq4_homography();
  H *= E(2, 2);  // the paper's normalization has h33 = 1.000021
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(H(r, c), E(r, c), 6e-4) << "h" << r + 1 << c + 1;
}

TEST(PhysicalHomography, PrintedP2SignGivesWrongTranslation) {
  PhysicalParams p = paper_physical_params();
  p.view[1].py = -100;
  Eigen::Matrix3d H = physical_homography(p) * paper_eq4_homography()(2, 2);
  EXPECT_NEAR(H(0, 2), -6.89, 0.05);  // eq. 4 prints 2.33
  EXPECT_NEAR(H(0, 0), paper_eq4_homography()(0, 0), 6e-4);
}

TEST(PhysicalHomography, FitRecoversHomographyFromPerturbedStart) {
  PhysicalParams truth = paper_physical_params();
  Eigen::Matrix3d H = physical_homography(truth);
  PhysicalParams start = truth;
  start.view[0].px += 200;
  start.view[0].py -= 50;
  start.view[0].alpha -= 0.17;
  start.view[0].beta -= 0.05;
  start.view[0].gamma += 0.5;
  Eigen::MatrixX2d s(25, 2);
  for (int i = 0; i < 25; ++i) s.row(i) << (i % 5) * 128.0, (i / 5) * 128.0;
  double rms = 1;
  PhysicalParams fit = fit_physical_params(H, start, s, false, &rms);
  EXPECT_LT(rms, 1e-3);
  Eigen::Matrix3d F = physical_homography(fit);
  for (int i = 0; i < 25; ++i) {
    Eigen::Vector3d a = H * Eigen::Vector3d(s(i, 0), s(i, 1), 1), b = F * Eigen::Vector3d(s(i, 0), s(i, 1), 1);
    EXPECT_LT((a.hnormalized() - b.hnormalized()).norm(), 1e-3);
  }
}

TEST(PhysicalHomography, RejectsImpossibleAngles) {
  PhysicalParams p = paper_physical_params();
  EXPECT_EQ(physical_params_problem(p), "");
  p.view[0].beta = -0.1;
  EXPECT_NE(physical_params_problem(p), "");
  p = paper_physical_params();
  p.view[1].res = 0;
  EXPECT_NE(physical_params_problem(p), "");
}
