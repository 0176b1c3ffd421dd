// Algebraic-error minimization for the affine trifocal tensor (Hartley & Zisserman alg. 16.2 in the
// affine form of Yang, Pan, Huang §3.3).
//
// With the epipoles e' = a4 (view 2) and e'' = b4 (view 3) fixed, T_i = a_i e''^T - e' b_i^T is linear in
// the remaining camera entries: t = E a, t the 16 affine entries (order of affine_nonzero_indices()), a the
// 14 entries a_1..a_2 (rows 1-2), a_3, b_1..b_2 (rows 1-2), b_3 that affine cameras leave free (the paper's
// 16 x 18 E without its four all-zero columns). Minimize ||A E a|| subject to ||E a|| = 1: SVD E = U D V^T,
// keep the columns U' of non-zero singular values, take y the smallest right singular vector of A U'
// (here: smallest eigenvector of U'^T A^T A U'), t = U' y. The epipoles, which for affine cameras are the
// directions e = (cos th, sin th, 0), are then refined by Levenberg-Marquardt (Ceres) over th', th'' on
// that algebraic error. Start: the epipoles of the affine-dlt tensor. A is the affine incidence matrix of
// trifocal_affine_dlt.hpp in isotropically normalized coordinates (views 1..3); output on the original
// pixels, unit norm. >= 4 tracks. On affine data the affine-dlt solution already satisfies the internal
// constraints, so the result equals it (tests/unit/geometry/trifocal_noise.cpp).
#pragma once
#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

TrifocalTensor trifocal_algebraic(const Eigen::MatrixXd& xy);

}  // namespace tpkit
