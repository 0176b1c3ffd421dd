// Synthetic cluster pairs for tests and benchmarks: the paper's setup (section 6) and variants with
// noise, extra points and missing points.
#pragma once
#include <Eigen/Core>
#include <cstdint>

namespace tpkit {

struct ClusterSynthOptions {
  int n = 100;           // points of cluster A before extra points are added
  double extent = 512;   // A is uniform in [0, extent]^2 pixels (image 1)
  double noise = 0;      // Gaussian noise (pixels, per coordinate) added to B
  double extra = 0;      // fraction of n: random points added to each cluster (within its bounding box)
  double missing = 0;    // fraction of the true points removed from B
  uint64_t seed = 1;
};

// A (image 1 pixels) and B ~ H A (image 2 pixels) with the options above; points shuffled so that the
// order carries no correspondence. `truth` receives H.
struct ClusterPair {
  Eigen::MatrixX2d A, B;
  Eigen::Matrix3d truth;
};
ClusterPair synth_cluster_pair(const Eigen::Matrix3d& H, const ClusterSynthOptions& o);

// A 5 x 5 grid over the bounding box of pts, where two homographies are compared.
Eigen::MatrixX2d extent_grid(const Eigen::MatrixX2d& pts);

}  // namespace tpkit
