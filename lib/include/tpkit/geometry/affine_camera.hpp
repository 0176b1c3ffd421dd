// Affine cameras x = M X + t (3x4 with last row 0 0 0 1) and synthetic affine three-view scenes with
// exact projections: the ground truth of the geometry tests and benchmarks.
//
// Views 1, 2, 3 are columns x1 y1, x2 y2, x3 y3; pixels x = column, y = row (origin at the centre of the
// top-left pixel); world points X in metres-like units of the generator (any unit: affine cameras absorb it).
#pragma once
#include <Eigen/Core>
#include <cstdint>

#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

// 3x4 affine camera from a 2x3 linear part M and a translation t (pixels).
Camera affine_camera(const Eigen::Matrix<double, 2, 3>& M, const Eigen::Vector2d& t);
// True if the third row is proportional to (0, 0, 0, 1).
bool is_affine_camera(const Camera& P, double tol = 1e-12);
// Projection of a Euclidean 3-D point (x = P (X, 1), divided by the third coordinate).
Eigen::Vector2d project(const Camera& P, const Eigen::Vector3d& X);

struct AffineSceneOptions {
  double image_size = 1000;     // images are image_size x image_size pixels (30000 for full satellite scenes)
  double relief = 0.15;         // terrain height range as a fraction of the ground extent (0: flat terrain)
  double max_view_angle = 0.35; // largest off-nadir angle of a view, radians (satellite along-track stereo)
  std::uint64_t seed = 1;
};

// A random triplet of satellite-like affine cameras (scaled orthographic views of a terrain patch with
// different off-nadir angles, rotations and anisotropic pixel scaling) whose images of the ground patch
// fill [0, image_size)^2, and the means to draw points on it.
struct AffineScene {
  CameraTriplet P;  // P[v] maps (X, Y, Z, 1) to homogeneous pixels of view v+1
  AffineSceneOptions options;
  double ground_extent = 1000;  // the patch is [0, ground_extent]^2 in X, Y

  static AffineScene random(const AffineSceneOptions& opt);
  // The same terrain with single-pass-like cameras: viewing directions (towards the satellite)
  // d_v ~ (tan c_v, tan a_v, 1), along-track a_v of -, 0, + (0.7..1) max_view_angle, cross-track
  // c_v = cross + spread U(-1, 1) (radians): spread 0 puts the three directions in one plane (the
  // camera centres at infinity collinear). Each camera: the orthographic view along d_v rolled by up
  // to 0.2 rad, anisotropic pixel scaling up to 5 %, scaled and shifted to fill the image.
  static AffineScene single_pass(const AffineSceneOptions& opt, double cross, double spread);
  // n random terrain points (smooth random relief of height range relief * ground_extent), n x 3.
  Eigen::MatrixXd points(int n, std::uint64_t seed) const;
  // Exact projections, n x 6 (x1 y1 x2 y2 x3 y3).
  Eigen::MatrixXd project(const Eigen::MatrixXd& X) const;
  // The true trifocal tensor (pixels).
  TrifocalTensor trifocal() const;
};

}  // namespace tpkit
