// The minimal parameterization of the affine trifocal tensor (Nordberg 2009, as used by Yang, Pan,
// Huang §3.1 eq. 7-10), optimized on the geometric (reprojection) error with Ceres.
//
// T = Tc x1 U x2 V x3 W, i.e. T_i = sum_m U(i, m) V Tc_m W^T, with U, V, W orthogonal and the core Tc
// sparse. Eq. 8-9 build the frames from the camera columns: U0 = (e12, ., [e12]_x e13), V0 = (e21,
// [e21]_x e23, .), W0 = (e31, [e31]_x e32, .), e_ij the image of camera centre j in view i (e12 ~ A^-1 a4,
// e21 = a4, e31 = b4, [a4]_x r ~ e21 x e23, ...); eq. 10 scales the columns to unit length. For affine
// cameras every epipole is a direction (third coordinate 0) and every trifocal line is the line at
// infinity (0, 0, 1), so the frames are U = (u1, u2, e_z), V = (v1, e_z, v3), W = (w1, e_z, w3) with u1,
// v1, w1 the epipole directions: each frame is one in-plane angle. The core then has 10 non-zero entries
// (17 zeros at fixed places: Tc_m(j, k) = 0 for j, k >= 2 because e' = V e_1, e'' = W e_1, plus the
// zeros that the choice u1 = e12 and the affine structure put in Tc_1 and Tc_2), 9 parameters up to scale.
// Parameters: 3 angles + 10 core entries on the unit sphere = 12 degrees of freedom, exactly those of
// three affine views; every parameter value is a valid affine tensor.
//
// Cost: the sum over tracks and views of squared reprojection errors (pixels; views 1..3 scaled by one
// common factor, so it is the pixel cost) with the 3-D points eliminated in closed form (affine cameras
// P = [I|0], P', P'' recovered from T via e' = V e_1, e'' = W e_1, as in camera_recovery.hpp).
// Start: the affine-dlt tensor's cameras. >= 4 tracks. Output on the original pixels, unit norm.
#pragma once
#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

struct MinimalParameterization {
  Eigen::Matrix3d U, V, W;
  TrifocalTensor core;
  int nonzero = 0;         // entries of the 10-entry pattern that are non-zero here
  double off_pattern = 0;  // largest entry outside the pattern relative to the largest (0 in theory)
};
// The 10 core entries (0-based T_i(j, k)) of an affine tensor: Tc_1: (1,1) (1,3); Tc_2: (1,1) (1,3)
// (3,1); Tc_3: (1,1) (1,2) (1,3) (2,1) (3,1) in 1-based (row, column). In coordinates where the three
// image origins are projections of one 3-D point (e.g. tracks centred on their centroids) the entries
// (1,1) (1,3) (3,1) of Tc_3 also vanish; they stay parameters.
bool minimal_core_entry(int i, int j, int k);
// Frames and core of a tensor of affine cameras given in a frame where P = [I|0] (e.g. from
// cameras_from_trifocal of an affine tensor). Exposed for tests.
MinimalParameterization minimal_parameterization(const CameraTriplet& P);

TrifocalTensor trifocal_minimal(const Eigen::MatrixXd& xy);

}  // namespace tpkit
