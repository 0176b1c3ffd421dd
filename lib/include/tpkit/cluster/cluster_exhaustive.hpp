// Exhaustive correspondence search for small clusters: every 4 points of A against every ordered 4
// points of B, the homography x_B ~ H x_A each 4 correspondences determine exactly (basis of the
// projective plane: H = M_B M_A^-1, with M the 3x3 matrix taking e1, e2, e3, (1,1,1) to the four points),
// and the remaining points of A scored by the verdict's statistic (cluster_verdict.hpp: their nearest
// free points of B, the binomial tail at the radius chosen from the data). That is C(|A|, 4) x P(|B|, 4)
// hypotheses (5 400 for 6 and 6 points, about 10^6 for 10 and 10), the complete set the verdict must
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

namespace tpkit {

// C(na, 4) x P(nb, 4), saturated at the largest long.
long exhaustive_hypothesis_count(long na, long nb);
// Clusters up to this many hypotheses are searched exhaustively by cluster-homog's default optimizer.
constexpr long kExhaustiveMaxHypotheses = 2000000;

struct ExhaustiveHypothesis {
  Eigen::Matrix3d H;                      // exact on its four correspondences
  std::vector<std::pair<int, int>> pairs; // (index in A, index in B), sorted: the four and the others matched
                                          // within the statistic's radius
  double log10_tail;                      // the verdict's statistic of the other points (lower is better)
};

// The `keep` best distinct hypotheses (distinct sets of pairs), best first; `tried` (if given) gets the number of homographies formed.
std::vector<ExhaustiveHypothesis> exhaustive_hypotheses(const ClusterCost& cost, bool allow_reflection, int keep = 8,
                                                        long* tried = nullptr);

}  // namespace tpkit
