// The general normalized linear algorithm for the trifocal tensor (Hartley & Zisserman alg. 16.1;
// Yang, Pan, Huang §3.2): 27 unknowns, four incidence equations per track,
// [x']_x (sum_i x^i T_i) [x'']_x = 0, solved by the eigenvector of A^T A with the smallest eigenvalue.
// `enforce` (default): the internal constraints are then imposed linearly (H&Z §16.3): the epipoles are
// taken from the linear tensor and the tensor is re-solved as T_i = a_i e''^T - e' b_i^T with those
// epipoles fixed (18 unknowns, rank 15), so that it is the tensor of three cameras. Without it the
// tensor has 26 degrees of freedom instead of 18, and cameras recovered from it (reproj-eval) fit
// noisy tracks badly: 3.9x the ML bound at 10 tracks, 1.56x at 100 (bench_trifocal --accuracy).
//
// Input: n x 6 pixels (views 1, 2, 3 = x1 y1, x2 y2, x3 y3), n >= 7. Each view is normalized
// isotropically (centroid to the origin, mean distance sqrt 2); the returned tensor is on the ORIGINAL
// pixels (normalization undone exactly with transform_trifocal), T[i](j, k) = T_i^{jk}, unit norm.
#pragma once
#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

constexpr int kDltMinTracks = 7;
TrifocalTensor trifocal_dlt(const Eigen::MatrixXd& xy, bool enforce = true);

}  // namespace tpkit
