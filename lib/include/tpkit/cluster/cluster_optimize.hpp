// Minimizers of the cluster cost (cluster_cost.hpp) over the homography x_B ~ H x_A between cluster A
// (image 1 pixels) and cluster B (image 2 pixels), in one of two parameterizations:
//   math      the 8 coefficients of H with h33 = 1 (the paper's "straight" method, section 3); random
//             steps act on H expressed in normalized coordinates (each cluster centred, mean distance
//             sqrt 2), +-0.05 per coefficient, since the paper gives no step for this method
//   physical  the parameters of physical_homography.hpp (12 extrinsic ones free, or all 20)
// Optimizers:
//   random    Navy et al. section 6: each iteration perturbs one free parameter drawn at random, by a
//             uniform step in +-1 m (px, py, rho), +-pi/10 rad (angles), +-1 % (res), +-1 px (cx, cy),
//             and keeps it when the cost decreases; stops at the target cost or the iteration limit.
//   default   global phase then local refinement: a (1+1) evolution strategy with step-size adaptation
//             from the start (cost estimated on at most 400 points per direction), then the robust local
//             refinement of H on the nearest-neighbour pairs (refine_on_pairs) until the pairs stop
//             changing; when that does not reach the target, the correspondence-free search
//             (cluster_search.hpp) supplies more starting points (refined by refine_growing), or for
//             clusters of up to about 10 points the exhaustive search (cluster_exhaustive.hpp, its best
//             hypotheses fitted by least squares to their matches, the verdict choosing), then
//             up to 5 more evolution rounds from the start; the best result is kept. Each stage stops at
//             the target cost or as soon as the verdict (cluster_verdict.hpp) accepts the best h with log10
//             odds >= 10. Steps of the evolution strategy to a degenerate h (MapCheck) are refused. For dense clusters
//             (> 2000 points) the search goes first: the cost is flat beyond the point spacing.
//   none      evaluates the start only.
// Deterministic for a seed.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "tpkit/cluster/cluster_cost.hpp"
#include "tpkit/cluster/cluster_verdict.hpp"
#include "tpkit/cluster/physical_homography.hpp"

namespace tpkit {

enum class Parameterization { Math, Physical };
enum class OptimizerKind { None, Random, Default };

struct OptimizeOptions {
  Parameterization param = Parameterization::Physical;
  OptimizerKind optimizer = OptimizerKind::Default;
  bool free_intrinsics = false;  // physical: 20 free parameters instead of 12
  double target = 0.25;          // cost (pixels) at which the search stops
  long max_iterations = 10000;   // random: iteration limit; default: evaluations of the global phase
  uint64_t seed = 1;
  bool search_fallback = true;   // default: use cluster_search when the start does not reach the target
  bool allow_reflection = false; // cluster_search: also mirror-image maps
};

// Where the optimization starts: physical parameters (from --init) and/or a homography.
struct OptimizeStart {
  bool has_physical = false;
  PhysicalParams physical;
  bool has_H = false;
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
};

struct OptimizeResult {
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();  // x_B ~ H x_A, h33 = 1
  bool has_physical = false;
  PhysicalParams physical;   // parameters giving H (physical parameterization only)
  double cost = 0;           // final cost (the ClusterCost's options), pixels
  double start_cost = 0;
  long iterations = 0;       // random: iterations; default: global evaluations + local rounds
  long evaluations = 0;      // cost evaluations (full or subsampled)
  int local_rounds = 0;      // rounds of refine_on_pairs
  double seconds = 0;
  bool reached_target = false;
  std::string method;        // what produced the result ("random", "global+local", "search+local", ...)
};

OptimizeResult optimize_clusters(const ClusterCost& cost, const OptimizeStart& start, const OptimizeOptions& opt);

// Local refinement of H on nearest-neighbour pairs (both directions, residual h(A_i) - B_j in image-2
// pixels) with a Cauchy loss of scale max(1.4826 median distance, 0.1 px) (with the cost's trim_from_data,
// the median of the distances the data-chosen trim keeps, data_trim()), solved by Ceres (LM) on the
// 8 coefficients of H in normalized coordinates (at most 3000 pairs per round, evenly strided);
// repeated until the pair set stops changing (or max_rounds). Without a region, keeps the best H by
// the cost. With a region (centre in image 1 pixels, radius), only pairs whose A point lies in it are
// used and the last H is returned. `rounds` (if given) gets the number of rounds.
struct RefineRegion {
  Eigen::Vector2d center;
  double radius;
};
// Least squares of the geometric error on the mutual nearest-neighbour pairs within 3 robust sigmas of
// their distances, repeated until that set stops changing: the precise map on partly overlapping
// clusters, where unmatched points keep the cost high and refine_on_pairs stops early. The default
// optimizer applies it when the target is not reached.
Eigen::Matrix3d polish_on_mutual_pairs(const ClusterCost& cost, const Eigen::Matrix3d& H, int max_rounds = 10);
Eigen::Matrix3d refine_on_pairs(const ClusterCost& cost, const Eigen::Matrix3d& H, int max_rounds = 30,
                                int* rounds = nullptr, const RefineRegion* region = nullptr);
// Least squares of the geometric error (image-2 pixels) on the given pairs (index in A, index in B),
// from H (Ceres, Levenberg-Marquardt, normalized coordinates); H itself when there are fewer than 4.
Eigen::Matrix3d fit_on_pairs(const ClusterCost& cost, const Eigen::Matrix3d& H,
                             const std::vector<std::pair<int, int>>& pairs);
// Region-growing refinement from a local hypothesis: refine_on_pairs on the region, doubling its radius
// until it covers cluster A, then on everything. With `support`, the hypothesis is given up (supported
// false, H as refined so far) when, from the second region on, the region's matches stay near chance
// (RegionSupport::log10_odds below kRegionMinLog10Odds): a right hypothesis, refined on its region,
// matches most of the region's points at the noise level, a wrong one a handful by chance; dropping it
// early is what keeps unrelated clusters, which refine every hypothesis of both searches, from costing
// seconds (1000 points: 5.7 s -> 0.4 s; 5000: 12 s -> 1.4 s).
constexpr double kRegionMinLog10Odds = 2;
struct GrownHypothesis {
  Eigen::Matrix3d H;
  bool supported;
};
GrownHypothesis refine_growing(const ClusterCost& cost, const Eigen::Matrix3d& H, RefineRegion region,
                               int* rounds = nullptr, const RegionSupport* support = nullptr);

// Similarity that centres pts and scales their mean distance to the centre to sqrt 2.
Eigen::Matrix3d normalizing_transform(const Eigen::MatrixX2d& pts);

}  // namespace tpkit
