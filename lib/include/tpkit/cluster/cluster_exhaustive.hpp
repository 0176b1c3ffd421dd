// Exhaustive correspondence search for small clusters: every s points of A against every ordered s
// points of B, the map x_B ~ H x_A of the model (cluster_model.hpp; s = 4 for a homography, 3 for an
// affine map, 2 for a similarity) each s correspondences determine exactly (H = M_B M_A^-1 with the
// model's frames; for a homography M takes e1, e2, e3, (1,1,1) to the four points),
// and the remaining points of A scored by the verdict's statistic (cluster_verdict.hpp: their nearest
// free points of B, the binomial tail at the radius chosen from the data). That is C(|A|, 4) x P(|B|, 4)
// hypotheses for a homography (5 400 for 6 and 6 points, about 10^6 for 10 and 10; C(|A|, s) x P(|B|, s)
// for the model), the complete set the verdict must
// count for clusters this small, where the quadruple search (cluster_search.hpp) has too few
// neighbourhoods to work from. Maps that tear cluster A apart (its points on both sides of the line at
// infinity) are skipped, and mirror images unless allowed. 4 points leave nothing to score: every
// hypothesis fits, and h is not determined.
// Pixels: x = column, y = row, image 1 for A, image 2 for B. Deterministic.
#pragma once
#include <Eigen/Core>
#include <utility>
#include <vector>

#include "tpkit/cluster/cluster_cost.hpp"
#include "tpkit/cluster/cluster_model.hpp"

namespace tpkit {

// C(na, s) x P(nb, s), saturated at the largest long (s: the model's minimal points).
long exhaustive_hypothesis_count(long na, long nb, ClusterModel model = ClusterModel::Homography);
// Clusters up to this many hypotheses are searched exhaustively by cluster-homog's default optimizer.
constexpr long kExhaustiveMaxHypotheses = 2000000;

struct ExhaustiveHypothesis {
  Eigen::Matrix3d H;                      // exact on its s correspondences
  std::vector<std::pair<int, int>> pairs; // (index in A, index in B), sorted: the four and the others matched
                                          // within the statistic's radius
  double log10_tail;                      // the verdict's statistic of the other points (lower is better)
};

// The `keep` best distinct hypotheses (distinct sets of pairs), best first; `tried` (if given) gets the number of homographies formed.
std::vector<ExhaustiveHypothesis> exhaustive_hypotheses(const ClusterCost& cost, bool allow_reflection, int keep = 8,
                                                        long* tried = nullptr,
                                                        ClusterModel model = ClusterModel::Homography);

}  // namespace tpkit
