// The map between two point clusters for a chosen model, or the simplest model the data support:
// cluster-homog's answer and its verdict (cluster_model.hpp, cluster_verdict.hpp).
//
// For each model tried:
//   homography   optimize_clusters (cluster_optimize.hpp), as cluster-homog always did;
//   similarity,  the exhaustive search over minimal sets (cluster_exhaustive.hpp) when the clusters are
//   affine      small enough (C(|A|, s) P(|B|, s) |A| |B| <= kLowModelExhaustiveWork), its best
//               hypotheses fitted by least squares to their matches; and, when a homography was found,
//               the model fitted to the homography's matches (fit_cluster_model_to_matches). On larger
//               clusters an explicit lower model runs the homography search first for that reason.
// Every candidate is judged by the verdict with its own model's minimal points. The homography's number
// of tests is its own search's, as cluster-homog always judged it (so every answer it accepted before is
// accepted still); a lower model's is every hypothesis any model evaluated (it is tried after or instead
// of the homography).
// Choice (`automatic`): the accepted candidate of fewest parameters that explains the matches as well as
// every richer candidate that is not degenerate (accepted or not): at least as many matches, and no
// significant gain from the richer model's extra parameters on its own matches, by the nested F test
// at level kModelTestLevel (both models fitted by least squares to the richer one's matches,
// F = ((RSS_low - RSS_rich) / d1) / (RSS_rich / d2), d1 = 2 (s_rich - s_low), d2 = 2k - 2 s_rich). A lower
// model that only approximates the map (an affine one of a projective map on 6 points) leaves
// residuals the richer one removes; one that is the map leaves the richer one only noise to overfit.
// When no candidate qualifies, the rejected one of highest log10 odds (reported as such): an accepted
// lower model that a rejected richer one fits far better is no answer.
// Deterministic for a seed.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "tpkit/cluster/cluster_cost.hpp"
#include "tpkit/cluster/cluster_model.hpp"
#include "tpkit/cluster/cluster_optimize.hpp"
#include "tpkit/cluster/cluster_verdict.hpp"

namespace tpkit {

constexpr double kModelTestLevel = 0.05;  // the nested F test: a richer model is needed below this p-value
constexpr double kLowModelExhaustiveWork = 2e8;  // hypotheses x |A| x |B| of a lower model's exhaustive search

struct SolveOptions {
  OptimizeOptions optimize;  // the homography's search (and the seed, the reflection choice)
  bool automatic = true;     // try every model and choose; else only `model`
  ClusterModel model = ClusterModel::Homography;
  double min_log10_odds = 3;  // the verdict's threshold
  double domain_area_b = 0;   // VerdictOptions::domain_area_b
};

struct ModelCandidate {
  ClusterModel model = ClusterModel::Homography;
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();  // x_B ~ H x_A, h33 = 1
  std::string method;   // "exhaustive+least squares", "fitted to the homography's matches", ...
  Verdict verdict;
};

struct ClusterSolution {
  ModelCandidate chosen;
  std::vector<ModelCandidate> candidates;  // the best of each model tried, fewest parameters first
  bool has_homography_search = false;       // optimize_clusters ran: `search` holds its result
  OptimizeResult search;
  long hypotheses = 0;                      // every hypothesis evaluated, all models
  double cost = 0;                          // the cluster cost of the chosen H (the ClusterCost's options)
};

ClusterSolution solve_clusters(const ClusterCost& cost, const OptimizeStart& start, const SolveOptions& opt);

}  // namespace tpkit
