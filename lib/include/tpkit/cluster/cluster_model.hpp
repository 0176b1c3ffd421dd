// The maps cluster-homog can fit between cluster A (image 1 pixels) and cluster B (image 2 pixels),
// each written as a 3x3 matrix x_B ~ H x_A (x = column, y = row):
//   similarity   rotation, one scale, translation: 4 parameters, fixed by 2 correspondences
//   affine       any linear map and a translation: 6 parameters, fixed by 3 (not collinear)
//   homography   8 parameters, fixed by 4 (no three collinear)
// A model with p parameters is fixed by s = p / 2 correspondences ("minimal points"): any s pairs fit it
// exactly, so the verdict (cluster_verdict.hpp) counts only the matches beyond s as evidence. A star
// field (astroalign's TestFewSources: 3 to 6 stars under a rotation and a shift) is verifiable by a
// similarity and not by a homography, which 4 points cannot over-determine.
//
// The minimal solver of every model is the same construction: a frame matrix M(q) of the model built
// from s points q (the map taking a canonical set of s points to them), and H = M(q_B) M(q_A)^-1:
//   similarity   M = [dx -dy x1; dy dx y1; 0 0 1], d = q2 - q1: takes (0,0), (1,0) to q1, q2
//                (mirrored frame [dx dy x1; dy -dx y1; 0 0 1] for orientation-reversing maps)
//   affine       M = [q1 q2 q3; 1 1 1] (columns): takes e1, e2, e3 (homogeneous) to q1, q2, q3
//   homography   the projective basis taking e1, e2, e3, (1,1,1) to q1..q4
#pragma once
#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

namespace tpkit {

class ClusterCost;

enum class ClusterModel { Similarity, Affine, Homography };

// "similarity", "affine", "homography".
const char* cluster_model_name(ClusterModel m);
// 2, 3, 4: the correspondences that fix the model.
int cluster_model_points(ClusterModel m);

// The frame matrix of the s = cluster_model_points(m) points P.row(idx[0..s-1]); false when the points
// cannot form one (coincident, collinear: triangle areas below 1e-9 of the squared spread).
// `mirrored` (similarity only) gives the orientation-reversing frame.
bool cluster_model_frame(ClusterModel m, const Eigen::MatrixX2d& P, const int* idx, Eigen::Matrix3d& M,
                         bool mirrored = false);

// Least squares of the geometric error (image-2 pixels) of the model on the pairs (index in A, index in
// B), starting from H (used by the homography's iterative fit, and returned when the pairs are fewer
// than the minimal points). The similarity is the closed form of Umeyama (1991) (with mirrors when H
// reverses orientation), the affine map linear least squares, the homography fit_on_pairs
// (cluster_optimize.hpp).
Eigen::Matrix3d fit_cluster_model(const ClusterCost& cost, ClusterModel m, const Eigen::Matrix3d& H,
                                  const std::vector<std::pair<int, int>>& pairs);

// The model fitted to the matches of H: mutual nearest neighbours under H within 3 robust sigmas of
// their distances, the model fitted to them, repeated until that set stops changing (at most
// `max_rounds`). How a similarity or an affine map is read off a homography the search found on
// clusters too large for the exhaustive search. False (out untouched) when fewer than s + 1 pairs
// qualify: nothing of the model could be fitted and verified.
bool fit_cluster_model_to_matches(const ClusterCost& cost, ClusterModel m, const Eigen::Matrix3d& H, Eigen::Matrix3d& out,
                                  int max_rounds = 10);

}  // namespace tpkit
