// Every trifocal method behind one name, with its minimum number of tracks and the input checks
// (trifocal_tensor.hpp: finite, no duplicated track, not a flat scene).
//
// Input n x 6 pixels, views 1, 2, 3 = x1 y1, x2 y2, x3 y3. Output T[i](j, k) = T_i^{jk} on the original
// pixels, Frobenius norm 1 (trifocal file convention).
#pragma once
#include <string>
#include <vector>

#include "tpkit/geometry/ransac.hpp"
#include "tpkit/geometry/trifocal_tensor.hpp"

namespace tpkit {

enum class TrifocalMethod { Dlt, AffineDlt, Algebraic, Minimal, ThreeF, Ml };

// "dlt", "affine-dlt", "algebraic", "minimal", "three-f", "ml"; throws UsageError otherwise.
TrifocalMethod parse_trifocal_method(const std::string& name);
std::string trifocal_method_name(TrifocalMethod m);
const std::vector<TrifocalMethod>& all_trifocal_methods();
// dlt 7, three-f 8, the affine methods 4.
int trifocal_min_tracks(TrifocalMethod m);

// Checks the input (check_trifocal_input; `check_noise_rank` = false skips the noise-level flatness test,
// for sets with outliers) and runs the method.
TrifocalTensor fit_trifocal(TrifocalMethod m, const Eigen::MatrixXd& xy, bool check_noise_rank = true);
// The method alone, no input checks (robust estimation calls it on inlier sets).
TrifocalTensor run_trifocal_method(TrifocalMethod m, const Eigen::MatrixXd& xy);

// Robust fitting (--ransac): hypotheses from minimal samples of 4 tracks by the affine ML solver (exact
// for 4 tracks), scored by MSAC on the per-track reprojection error sqrt((|r1|^2 + |r2|^2 + |r3|^2) / 3)
// in pixels (points eliminated in closed form: for affine views this is the reprojection error after
// optimal triangulation), LO re-fits by ml; the inliers of the best (LO-refined) model are the inlier
// mask, and they are re-fitted with `m` (with the full input checks, flat terrain included).
// A robust fit is refused (NumericalError) unless its inliers exceed its 4-track minimal sample by at
// least kRobustMinSupport tracks and by at least kRobustMinFraction of all tracks.
constexpr size_t kRobustMinSupport = 4;
constexpr double kRobustMinFraction = 0.01;
struct RobustTrifocalFit {
  TrifocalTensor T;
  std::vector<char> inlier;
  size_t inliers = 0;
  int iterations = 0;
};
RobustTrifocalFit fit_trifocal_ransac(TrifocalMethod m, const Eigen::MatrixXd& xy, const RansacOptions& opt);

}  // namespace tpkit
