// Reprojection evaluation of a trifocal tensor (Yang, Pan, Huang §2.3): recover the cameras from the
// tensor (camera_recovery.hpp: P = [I|0], P', P'' with unit third rows), triangulate every track by DLT
// (triangulate.hpp), reproject, and summarize.
//
// Views 1, 2, 3 = columns x1 y1, x2 y2, x3 y3; tensor on pixels (trifocal file convention). Residual =
// reprojected minus observed, pixels. RMSE = sqrt( (1 / 3n) sum_tracks sum_views (dx^2 + dy^2) ), the root
// mean squared 2-D residual over all tracks and views (per-coordinate RMSE = RMSE / sqrt 2).
#pragma once
#include "tpkit/core/text_table.hpp"
#include <Eigen/Core>
#include <string>
#include <vector>

#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

// The cameras of a tensor in a conditioned frame: view v pixels x are mapped by x^ = H_v x (shift to
// the centroid of the normalization tracks, one common scale s for all views, so that residuals keep
// equal weight); cameras are recovered from the tensor of that frame. Pixel residual = frame residual / s.
struct ReprojectionFrame {
  std::vector<Eigen::Matrix3d> H;
  double scale = 1;
  CameraTriplet P;       // cameras of the conditioned frame (unit third rows)
  CameraTriplet P_pixels;  // the same cameras on pixels, first camera [I|0]
};
ReprojectionFrame reprojection_frame(const TrifocalTensor& T, const Eigen::MatrixXd& normalization_tracks);

struct ReprojectionStats {
  long n = 0;
  double rmse = 0;                  // as defined above, pixels
  std::array<double, 3> rmse_view{};  // sqrt(mean over tracks of dx^2 + dy^2) in view v
  double median = 0;                // median of the 3n 2-D residual lengths
  double max = 0;                   // largest 2-D residual length
};

struct ReprojectionResult {
  Eigen::MatrixXd residual;  // n x 6: dx1 dy1 dx2 dy2 dx3 dy3 (reprojected - observed), pixels
  Eigen::VectorXd track_rms; // per track sqrt((|r1|^2 + |r2|^2 + |r3|^2) / 3), pixels
  Eigen::MatrixXd X;         // n x 4 homogeneous points of the conditioned frame
  ReprojectionStats stats;
};

// Evaluates n x 6 tracks. Throws NumericalError if a track cannot be triangulated.
ReprojectionResult evaluate_reprojection(const ReprojectionFrame& frame, const Eigen::MatrixXd& xy);
ReprojectionStats reprojection_stats(const Eigen::MatrixXd& residual);

// The error distribution figure (after Yang, Pan, Huang figs. 3-8), drawn by core/residual_field.hpp:
// per view a residual field (16 x 16 cells over the image, one exaggeration for every panel, RMSE, median
// and p90 above each panel), the fit set in one row and `check` (may be empty) in a second; and a
// histogram of the 2-D residual lengths of both sets, each normalised, on a log axis. `images` (may be
// empty) gives the views' sizes, else the points' extent is the frame.
void plot_reprojection(const std::string& path, const Eigen::MatrixXd& xy, const Eigen::MatrixXd& residual,
                       const Eigen::MatrixXd& check_xy, const Eigen::MatrixXd& check_residual, const std::string& title,
                       const std::vector<ImageRef>& images = {});

}  // namespace tpkit
