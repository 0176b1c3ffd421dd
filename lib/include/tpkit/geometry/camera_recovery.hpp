// Cameras and epipoles from a trifocal tensor (Yang, Pan, Huang §2.3; Hartley & Zisserman alg. 15.1).
//
// Views 1, 2, 3 as in trifocal_tensor.hpp; the tensor acts on homogeneous pixels of whatever frame it
// was written in (the cameras come out in that same frame).
#pragma once
#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

struct TrifocalEpipoles {
  Eigen::Vector3d e2;  // e'  : image of camera centre 1 in view 2, unit norm (e'^T [u1 u2 u3] = 0)
  Eigen::Vector3d e3;  // e'' : image of camera centre 1 in view 3, unit norm (e''^T [v1 v2 v3] = 0)
};
// u_i, v_i: left and right null vectors of T_i (smallest singular vectors).
TrifocalEpipoles trifocal_epipoles(const TrifocalTensor& T);

// P = [I|0], P' = [[T1 e'', T2 e'', T3 e''] | e'], P'' = [(e'' e''^T - I)[T1^T e', T2^T e', T3^T e'] | e''],
// each then scaled so that its third row has unit norm (equal weight of the views in DLT triangulation).
// A projective frame: the cameras reproduce the tensor up to scale.
CameraTriplet cameras_from_trifocal(const TrifocalTensor& T);

// F21 = [e']_x [T1 e'', T2 e'', T3 e'']: x'^T F21 x = 0 for a view-1 point x and its view-2 match x'.
Eigen::Matrix3d fundamental21_from_trifocal(const TrifocalTensor& T);

// Camera centre (null vector of P), unit norm.
Eigen::Vector4d camera_centre(const Camera& P);

// Maps cameras of normalized images (x^ = H_v x) back to pixels: P_v = H_v^-1 P^_v diag(H_1, 1), so that
// the first camera stays [I|0] when it was.
CameraTriplet denormalize_cameras(const CameraTriplet& P, const std::vector<Eigen::Matrix3d>& H);

}  // namespace tpkit
