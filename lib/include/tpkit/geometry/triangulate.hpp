// Linear (DLT) triangulation of a point seen in several views and its reprojection residuals.
//
// Cameras P_v map homogeneous 3-D points to homogeneous pixels of view v (views in the order given);
// points are pixels (x, y) of the same frames. Units: pixels of those frames.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

// X minimizing ||D X|| with ||X|| = 1, D = [x P^3 - P^1; y P^3 - P^2] per view (SVD of D; Yang, Pan,
// Huang §2.3). `pts` is 1 x 2K (x1 y1 x2 y2 ...), one pair per camera.
Eigen::Vector4d triangulate_dlt(const CameraTriplet& P, const Eigen::Matrix<double, 1, 6>& pts);

// Reprojected minus observed, 1 x 6 (dx1 dy1 dx2 dy2 dx3 dy3). Throws NumericalError when the point
// reprojects to infinity in a view.
Eigen::Matrix<double, 1, 6> reprojection_residual(const CameraTriplet& P, const Eigen::Vector4d& X,
                                                  const Eigen::Matrix<double, 1, 6>& pts);

}  // namespace tpkit
