// The general normalized linear algorithm for the trifocal tensor (Hartley & Zisserman alg. 16.1 without
// the constraint step; Yang, Pan, Huang §3.2): 27 unknowns, four incidence equations per track,
// [x']_x (sum_i x^i T_i) [x'']_x = 0, solved by the eigenvector of A^T A with the smallest eigenvalue.
//
// Input: n x 6 pixels (views 1, 2, 3 = x1 y1, x2 y2, x3 y3), n >= 7. Each view is normalized
// isotropically (centroid to the origin, mean distance sqrt 2); the returned tensor is on the ORIGINAL
// pixels (normalization undone exactly with transform_trifocal), T[i](j, k) = T_i^{jk}, unit norm.
#pragma once
#include "tpkit/trifocal_tensor.hpp"

namespace tpkit {

constexpr int kDltMinTracks = 7;
TrifocalTensor trifocal_dlt(const Eigen::MatrixXd& xy);

}  // namespace tpkit
