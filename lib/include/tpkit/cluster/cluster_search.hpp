// Correspondence-free global search for the homography x_B ~ H x_A between cluster A (image 1 pixels)
// and cluster B (image 2 pixels), with no starting point.
//
// Local affine invariants of quadruples of near neighbours: for each anchor point, quadruples made of
// the anchor and three of its k nearest neighbours (k_a in A, k_b > k_a in B so that an anisotropic
// map still keeps them among the neighbours). For four points, the areas of the four triangles that
// leave out one point each scale by the same factor under any affine map, so the three smaller areas
// divided by the largest, sorted, are an affine invariant (2 degrees of freedom); sorting them also
// orders the four points. Quadruples of A are matched to those of B by nearest descriptors (nanoflann
// KD-tree in descriptor space); each match gives an affine hypothesis (least squares on the four
// points), gated by the forward truncated distance of the anchor's 8 nearest neighbours in A and scored
// by the forward distance truncated at a third of the gate of the anchor's `local` nearest neighbours
// in A other than the quadruple's own four (which every hypothesis fits), and the best are kept; they start the region-growing refinement (cluster_optimize.hpp). A mildly projective map (the paper's eq. 4) is locally affine, so the hypotheses start the
// local refinement (cluster_optimize.hpp) inside its basin. Handles any rotation and scale and
// anisotropy; orientation-reversing maps (mirror images) too when allow_reflection is set.
// Deterministic for a seed.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "tpkit/cluster/cluster_cost.hpp"

namespace tpkit {

struct SearchOptions {
  int k_a = 5;               // neighbours of an anchor in A
  int k_b = 8;               // neighbours of an anchor in B
  int max_anchors_a = 150;   // anchors of A used (random subset beyond that)
  int max_anchors_b = 4000;  // anchors of B used
  int matches_per_quad = 8;  // nearest descriptors of B tried per quadruple of A
  int keep = 12;             // hypotheses returned (best first)
  int local = 30;            // neighbours of the anchor that score a hypothesis
  bool allow_reflection = false;
  uint64_t seed = 1;
  int widen = 1;             // > 1: a wider second search (cluster_optimize): dense clusters (B over 2000
                             // points) take widen times the anchors, sparse ones 2 and 4 more neighbours
};

struct SearchHypothesis {
  Eigen::Matrix3d H;  // x_B ~ H x_A
  double score;       // mean truncated forward distance near the quadruple (pixels), lower is better
  Eigen::Vector2d center;  // the quadruple's anchor in A (image 1 pixels)
  double radius;           // radius of the neighbourhood where the score was measured (image 1 pixels)
};

// Best hypotheses first; `tried` (if given) gets the number of hypotheses scored.
std::vector<SearchHypothesis> search_hypotheses(const ClusterCost& cost, const SearchOptions& opt,
                                                long* tried = nullptr);

}  // namespace tpkit
