// Whether a homography found between two point clusters is an answer: the verdict of cluster-homog.
//
// A cost value cannot say it (a correct partial-overlap answer may cost 9-61 px while an unrelated pair
// costs 0.8 px). The verdict counts the points the homography matches and asks how often unrelated
// clusters of the same densities would match as many, as astrometry.net verifies a field:
//   - a degenerate h is refused outright (degeneracy()): its line at infinity (h3 . x = 0) must not cross
//     cluster A (nor that of h^-1 cross B), and neither h(hull A) nor h^-1(hull B) may shrink below
//     kMinAreaRatio of the smaller of the two hulls' areas (a cluster collapsed onto a few points);
//   - inliers k(r): points of A whose forward nearest neighbour in B is mutual and within r, for
//     r = s/32, s/16, s/8, s/4 with s = sqrt(area(hull B) / |B|), B's mean spacing; candidates n: the
//     points of A that h maps inside hull B;
//   - for unrelated clusters, a mapped point has a B point within r with probability
//     p = 1 - exp(-pi r^2 |B| / area(hull B)) (Poisson); any homography fits 4 matches exactly (8
//     parameters), so those prove nothing: the chance of the result is the binomial tail
//     P = P(K >= k - 4), K ~ Bin(n - 4, p), and the number of false alarms is
//     NFA = 4 radii x max(1, hypotheses tried) x P;
//   - accepted when log10_odds = -log10(NFA) >= min_log10_odds (default 3), at the best radius.
// Nothing here depends on the cost's --trim or --truncate. Pixels: x = column, y = row; H is x_B ~ H x_A.
// Clusters of 4 to 6 points cannot be verified this way (at most 2 matches beyond the 4 fitted ones).
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "tpkit/cluster_cost.hpp"

namespace tpkit {

struct VerdictOptions {
  double min_log10_odds = 3;  // accept when -log10(NFA) reaches this
  long hypotheses = 1;        // how many homographies the search evaluated (the NFA's number of tests)
};

struct Verdict {
  bool accepted = false;
  std::string degenerate;   // why h is degenerate, "" if it is not
  int inliers = 0;          // k at the chosen radius
  int candidates = 0;       // n: points of A mapped inside hull B
  double radius_px = 0;     // the radius of the best significance
  double expected = 0;      // chance inliers at that radius: 4 + (n - 4) p
  double log10_odds = 0;    // -log10(NFA); -inf for a degenerate h
};

constexpr double kMinAreaRatio = 1e-3;

// "" when H is a usable map between the clusters, else the reason (line at infinity across a cluster,
// a cluster collapsed). MapCheck keeps the clusters' hulls for many maps (the search's hypotheses).
class MapCheck {
 public:
  MapCheck(const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B);
  std::string operator()(const Eigen::Matrix3d& H) const;
  const std::vector<Eigen::Vector2d>& hull_b() const { return hull_b_; }  // counter-clockwise
  double area_b() const { return area_b_; }

 private:
  std::vector<Eigen::Vector2d> hull_a_, hull_b_;
  double area_a_ = 0, area_b_ = 0;
};
std::string degeneracy(const Eigen::Matrix3d& H, const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B);

Verdict judge_homography(const ClusterCost& cost, const Eigen::Matrix3d& H, const VerdictOptions& opt = {});

}  // namespace tpkit
