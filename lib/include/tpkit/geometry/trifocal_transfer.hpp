// Point transfer with a trifocal tensor (Hartley & Zisserman alg. 16.?, the trilinearities of the ISPRS
// 2000 fragment): from a view-1 point x and its view-2 match x', the view-3 point
//   x''^k = x^i l'_j T_i^{jk},
// with l' the line through x' perpendicular to the epipolar line F21 x (point-line-point). Before that,
// (x, x') are moved onto the epipolar geometry of the tensor by the first-order (Sampson) correction,
// which is exact for affine epipolar geometry.
#pragma once
#include <Eigen/Core>

#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

// pairs: n x 4 pixels (x1 y1 x2 y2); returns n x 2 pixels (x3 y3) of view 3. The tensor acts on pixels
// (trifocal file convention). Conditioning: the computation runs in coordinates shifted to the pairs'
// centroids and scaled by one common factor, which changes nothing but rounding. Throws NumericalError
// when a point transfers to infinity (x on the epipolar line of ... degenerate) or the tensor is singular.
Eigen::MatrixXd transfer_point_line_point(const TrifocalTensor& T, const Eigen::MatrixXd& pairs);

}  // namespace tpkit
