// The maximum-likelihood affine fit of three views (Tomasi-Kanade factorization; Hartley & Zisserman
// alg. 18.1): with every point seen in all three views and isotropic Gaussian pixel noise, the rank-3
// approximation (SVD) of the centred 6 x n measurement matrix is the ML estimate of the three affine
// cameras and the points, so no bundle adjustment can lower its reprojection error.
//
// Input n x 6 pixels (views 1..3 = x1 y1, x2 y2, x3 y3), n >= 4. Conditioning shifts each view to its
// centroid and scales all views by ONE factor (per-view factors would change the weighting and the
// result would no longer be ML in pixels). Output: affine cameras on pixels (x_v = P_v (X, 1)), the points
// (n x 3, the factorization's affine frame) and the tensor of the cameras (eq. 6 structure), unit norm.
#pragma once
#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

constexpr int kMlMinTracks = 4;

struct AffineTrifocalFit {
  CameraTriplet P;   // affine cameras, pixels
  Eigen::MatrixXd X; // n x 3
  TrifocalTensor T;  // pixels, unit norm
  // singular values of the centred measurement matrix (conditioned frame), descending
  Eigen::Matrix<double, 6, 1> singular_values;
};

AffineTrifocalFit trifocal_ml(const Eigen::MatrixXd& xy);
TrifocalTensor trifocal_ml_tensor(const Eigen::MatrixXd& xy);

// The ML residual of the affine model with the points eliminated: for centred, commonly scaled
// measurements the per-track residual is Q (x - t) with Q the projector onto the complement of the
// camera columns (6 x 6). Used by the robust estimator.
struct AffineProjector {
  Eigen::Matrix<double, 6, 6> Q;  // on pixels
  Eigen::Matrix<double, 6, 1> t;  // camera translations (pixels), x1 y1 x2 y2 x3 y3
  // Sum over the three views of the squared 2-D reprojection error of a track (pixels^2).
  double squared_error(const double* track6) const;
};
AffineProjector affine_projector(const CameraTriplet& affine_cameras);

}  // namespace tpkit
