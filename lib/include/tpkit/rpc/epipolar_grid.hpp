// Epipolar curves of many pixels at once: image a's pixels -> image b, by interpolation in a grid of
// exact curve points.
//
// RPC-guided matching (match/rpc_guided_matching.hpp) needs, for every keypoint of image a, the pixels of
// image b that see its line of sight at a few heights: a localization (Gauss-Newton, about 4.4 projections
// with Jacobian) and a projection per height, 5 heights per keypoint, 120 000 of each for a 1024² Pléiades
// pair (24 000 keypoints): 9 % of tp-match's time on the Marseille triplet. The map (x, y, h) -> pixel of
// b is smooth (two rational cubics and the inverse of one), so it is computed exactly at the nodes of a
// grid (x, y every `spacing` pixels of a over the box asked for, `levels` heights evenly over the height
// range) and interpolated trilinearly between them.
//
// The interpolation is checked, not assumed: at one point inside every grid cell (its centre, at a
// height midway between two levels, the level pair turning from cell to cell) the exact curve point is
// computed too; when the largest difference exceeds `tolerance` pixels the grid is built again at half
// the spacing and twice the level intervals (at most `refinements` times), and when it still exceeds it
// the grid is not used (ok() false: the caller computes exact curve points). A node whose localization
// fails makes the eight cells around it unusable (point() false there), nothing else.
// Marseille, img_01 -> img_02, heights 40..1090 m (the models' common range), largest error at 3000 random
// points: 1.1e-2 px with 2 levels, 7.2e-4 with 5, 2.2e-4 with 9 at 128-pixel spacing (1.9e-4 at 64): the
// curves' bend along the heights, not the spacing, sets the error; 41..345 m: 5.4e-5 px (9 levels, 128).
//
// Units: pixels in tpkit's convention in both images (x = column, y = row, (0, 0) the centre of the
// top-left pixel), heights in metres above the ellipsoid (the models' own).
#pragma once
#include <Eigen/Core>
#include <vector>

#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

struct EpipolarGridOptions {
  double spacing = 128;      // pixels of image a between nodes
  int levels = 9;            // heights over the range (>= 2)
  double tolerance = 1e-3;   // pixels of image b: largest interpolation error accepted at the check points
  int refinements = 2;       // times the grid may be rebuilt finer before it is given up
  long max_nodes = -1;       // > 0: a grid of more nodes is not built (cheaper to compute the points exactly)
};

class EpipolarGrid {
 public:
  // Pixels [x0, x1] x [y0, y1] of image a, heights [h_lo, h_hi]; `threads` workers build it.
  EpipolarGrid(const RpcModel& a, const RpcModel& b, double x0, double y0, double x1, double y1, double h_lo, double h_hi,
               const EpipolarGridOptions& o, int threads);
  // The grid passed its check (else point() is always false).
  bool ok() const { return ok_; }
  // The pixel of b that sees the ground point of pixel (x, y) of a at height h; false outside the box
  // or the height range, in a cell next to a failed node, or when the grid is not ok().
  bool point(double x, double y, double h, Eigen::Vector2d& q) const;
  // Largest difference from the exact curve point at the check points of the grid in use, pixels of b.
  double check_error() const { return check_error_; }
  double spacing() const { return step_; }
  int levels() const { return nh_; }

 private:
  bool build(const RpcModel& a, const RpcModel& b, double step, int levels, double tolerance, int threads);
  double x0_, y0_, x1_, y1_, h_lo_, h_hi_;
  double step_ = 0, dh_ = 0;
  int nx_ = 0, ny_ = 0, nh_ = 0;  // nodes along x, y and height
  std::vector<Eigen::Vector2d> q_;  // node (i, j, k) at ((k * ny + j) * nx + i); NaN where localization failed
  bool ok_ = false;
  double check_error_ = 0;
};

}  // namespace tpkit
