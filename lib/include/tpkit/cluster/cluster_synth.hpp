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

// The star-field families of issue 15 (the benchmark's and the tests'): x_B ~ H x_A with H = a
// similarity of any rotation and of scale 0.3..3 (log-uniform) about the centre of [0, extent]^2, then
// anisotropy (x scale / y scale) uniform in [1, aniso], projective terms h31, h32 uniform in
// +-proj / extent, and the centre taken to (1000, 1000). Deterministic for a seed.
Eigen::Matrix3d random_family_homography(double aniso, double proj, double extent, uint64_t seed);

// A 5 x 5 grid over the bounding box of pts, where two homographies are compared.
Eigen::MatrixX2d extent_grid(const Eigen::MatrixX2d& pts);

}  // namespace tpkit
