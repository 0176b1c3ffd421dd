// The symmetric nearest-neighbour cost of Navy et al. (2005), eq. 3, between two point clusters:
//   C(h) = 1/N sum_i min_j d(h(P_i), P'_j) + 1/N' sum_j min_i d(h^-1(P'_j), P_i)
// with cluster A = {P_i} in image 1 and cluster B = {P'_j} in image 2 (pixels, x = column, y = row),
// h the homography x_B ~ H x_A. Each term is a mean distance in pixels: forward ones in image-2
// pixels, backward ones in image-1 pixels. Nearest neighbours come from nanoflann KD-trees built once
// per cluster, so one evaluation is O((N + N') log N) instead of the paper's O(N N'); the trimmed mean
// selects with nth_element (O(N)), no sort.
//
// Robust variants, for clusters with extra and missing points:
//   trim F      each direction averages only the smallest (1 - F) fraction of its distances
//   truncate T  each distance is replaced by min(d, T) pixels
//   from data   (trim_from_data; cluster-homog's default) the trim of each direction is chosen by the
//               data, for every h: of the direction's N distances sorted d_(1) <= ... <= d_(N), the k
//               smallest are kept where k minimizes psi(k) = mean(d_(1..k)) / (k/N)^1.5, k from
//               min(N, max(4, N/10)) to N, and the direction's term is that least psi (Chetverikov's
//               trimmed ICP criterion e(xi) / xi^(1 + lambda), lambda = 2, on distances instead of their
//               squares). The matched fraction xi = k/N is thus estimated, not given: an unknown overlap.
//               psi(N) is the paper's mean, so a fully overlapping pair costs what eq. 3 gives.
// Points that h sends to (or beyond) the line at infinity count as the largest distance (see cap()).
#pragma once
#include <Eigen/Core>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "tpkit/cluster/cluster_model.hpp"

namespace tpkit {

struct CostOptions {
  double trim = 0;      // fraction in [0, 1) of the largest distances left out in each direction
  double truncate = 0;  // pixels; 0 = no truncation
  bool trim_from_data = false;  // each direction's trim estimated per h (see above); needs trim = truncate = 0
};

// The data-chosen trim of one direction: how many of the distances d (any order; reordered) psi keeps,
// and psi itself (pixels). d must not be empty.
struct DataTrim {
  size_t keep;
  double psi;
};
DataTrim data_trim(std::vector<double>& d);

// One nearest-neighbour pair under h: point ia of A and ib of B; d is the distance in pixels measured
// in the image of the query (forward: |h(A_ia) - B_ib| in image 2; backward: |h^-1(B_ib) - A_ia|).
struct NnPair {
  int ia, ib;
  double d;
  bool forward;
};

class ClusterCost {
 public:
  // A: n x 2 pixels of image 1, B: m x 2 pixels of image 2; each needs at least one point.
  ClusterCost(const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B, CostOptions opt = {});
  ~ClusterCost();
  ClusterCost(const ClusterCost&) = delete;
  ClusterCost& operator=(const ClusterCost&) = delete;

  // Eq. 3 (with the robust variant of the options); H is x_B ~ H x_A. +inf if H is singular.
  double operator()(const Eigen::Matrix3d& H) const;
  double cost(const Eigen::Matrix3d& H, const CostOptions& opt) const;
  // The same estimated from a subset of A (forward terms) and of B (backward terms), indices into A and B;
  // a null subset means all points.
  double cost(const Eigen::Matrix3d& H, const CostOptions& opt, const std::vector<int>* sub_a,
              const std::vector<int>* sub_b) const;
  // The fractions of A's and B's points that the data-chosen trim keeps under H (trim_from_data).
  std::pair<double, double> kept_fractions(const Eigen::Matrix3d& H) const;
  // Every nearest-neighbour pair of both directions under H (n forward then m backward).
  std::vector<NnPair> pairs(const Eigen::Matrix3d& H) const;
  // Forward-only mean of min(d, tol) over a subset of A (indices), for quick hypothesis scoring.
  double forward_truncated(const Eigen::Matrix3d& H, const std::vector<int>& subset, double tol) const;
  // Nearest neighbour in B of an image-2 point / in A of an image-1 point: index, squared distance.
  int nearest_b(const double* q, double* d2) const;
  int nearest_a(const double* q, double* d2) const;

  const Eigen::MatrixX2d& a() const { return A_; }
  const Eigen::MatrixX2d& b() const { return B_; }
  const CostOptions& options() const { return opt_; }
  // Distance used for a point mapped to infinity: the larger bounding-box diagonal of A and B.
  double cap() const { return cap_; }
  // Every index of A (of B) once, in the order of the KD-tree's leaves: points close in space are close
  // in it. Nearest-neighbour queries of whole clusters made in this order hit the cache (about 5x faster
  // at 10^6 points than the index order of unsorted input); the results do not depend on the order.
  const std::vector<int>& order_a() const { return order_a_; }
  const std::vector<int>& order_b() const { return order_b_; }

 private:
  struct Trees;
  // Nearest-neighbour distances of both directions under H (Hi its inverse), at their points' indices
  // (or in the subsets' order); points sent to infinity get 10 cap().
  void distances(const Eigen::Matrix3d& H, const Eigen::Matrix3d& Hi, const std::vector<int>* sub_a,
                 const std::vector<int>* sub_b, std::vector<double>& da, std::vector<double>& db) const;
  Eigen::MatrixX2d A_, B_;
  CostOptions opt_;
  double cap_ = 1;
  std::unique_ptr<Trees> trees_;
  std::vector<int> order_a_, order_b_;
  std::vector<double> xy_a_, xy_b_;  // coordinates in order_a_ / order_b_, x y interleaved
};

// The mutual nearest neighbours under H: A_ia's nearest in B is B_ib and B_ib's nearest in A (under
// H^-1) is A_ia; d is the forward distance in image-2 pixels. Sorted by ia.
struct MutualPair {
  int ia, ib;
  double d;
};
std::vector<MutualPair> mutual_pairs(const ClusterCost& cost, const Eigen::Matrix3d& H);

// Throws InputError(source, 0, reason) unless the cluster can define a map of the model
// (cluster_model.hpp): at least cluster_min_points(model) points (3 for a similarity, 4 for an affine
// map, 4 for a homography, which 4 points fix but cannot verify), all finite, not all on one line
// (spread across the principal axis above 1e-6 of the spread along it).
int cluster_min_points(ClusterModel model);
void validate_cluster(const Eigen::MatrixX2d& pts, const std::string& source,
                      ClusterModel model = ClusterModel::Homography);

// Largest distance between h and a reference homography over the points of `pts` (image 1), in
// image-2 pixels (used for "h within 0.5 px of the truth over the cluster's extent").
double homography_max_difference(const Eigen::Matrix3d& H, const Eigen::Matrix3d& ref, const Eigen::MatrixX2d& pts);
// The same as a root mean square over the points (issue 15's "h within 0.5 px RMS of the truth over A's
// extent", with pts = extent_grid(A)); +inf if a point goes to infinity under either.
double homography_rms_difference(const Eigen::Matrix3d& H, const Eigen::Matrix3d& ref, const Eigen::MatrixX2d& pts);

}  // namespace tpkit
