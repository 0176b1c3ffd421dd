// Whether a homography found between two point clusters is an answer: the verdict of cluster-homog.
//
// A cost value cannot say it (a correct partial-overlap answer may cost 9-61 px while an unrelated pair
// costs 0.8 px). The verdict counts the points the homography matches and asks how often unrelated
// clusters of the same densities would match as many, as astrometry.net verifies a field and as
// AC-RANSAC (Moisan, Moulon, Monasse 2012) chooses its inlier radius from the data:
//   - a degenerate h is refused outright (degeneracy()): its line at infinity (h3 . x = 0) must not cross
//     cluster A (nor that of h^-1 cross B), and neither h(hull A) nor h^-1(hull B) may shrink below
//     kMinAreaRatio of the smaller of the two hulls' areas (a cluster collapsed onto a few points);
//   - trials n = |A|, every point of A (not only those h maps into B: a map the search chose can push
//     the points it does not fit out of B, and be judged on the few it keeps); matches: the points of A
//     whose forward nearest neighbour in B is mutual, with their distances d_1 <= d_2 <= ... (image-2
//     pixels); s = sqrt(area(hull B) / |B|) is B's mean spacing;
//   - for unrelated clusters, a mapped point has a B point within r with probability
//     p(r) = 1 - exp(-pi r^2 |B| / area(D)) (Poisson), D the field of B: its image when the points file
//     gives the image's size (AC-RANSAC's alpha = pi r^2 / image area; a star could have been anywhere
//     in the frame), else hull B (which understates a few points' field: 3 points span about a twelfth of
//     it); any homography fits 4 matches exactly (8
//     parameters), so those prove nothing: with the radius r = d_k of the k-th match (k = 5 ... n,
//     floored at 1e-6 s), the chance of k matches is the binomial tail
//     P_k = P(K >= k - 4), K ~ Bin(n - 4, p(d_k / sqrt(1 - 4/k))), the radius widened because h is
//     fitted to its matches by least squares (8 parameters leave 2k - 8 of the 2k residuals' degrees
//     of freedom: 5 points fitted to 0.05 px are no closer than 4 exact and a fifth at 0.11 px); the
//     number of false alarms is
//     NFA = max(1, n - 4) radii x max(1, hypotheses tried) x min_k P_k;
//   - accepted when log10_odds = -log10(NFA) >= min_log10_odds (default 3).
// The radius comes from the data, so a small cluster measured to 0.1 px is verifiable: 6 points (2
// matches beyond the 4 fitted) within 0.1 px of each other. With 4 points nothing is left to verify (any
// 4 correspondences fit exactly), so such an answer is always rejected: 4 points do not determine h.
// For a lower model (VerdictOptions::model, cluster_model.hpp) with s minimal points, s replaces 4
// throughout: P_k = P(K >= k - s), K ~ Bin(n - s, p(d_k / sqrt(1 - s/k))), max(1, n - s) radii, and
// "undetermined" below s + 1 points mapped into B (a similarity is verifiable from 3 points).
// Nothing here depends on the cost's --trim or --truncate. Pixels: x = column, y = row; H is x_B ~ H x_A.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "tpkit/cluster/cluster_cost.hpp"
#include "tpkit/cluster/cluster_model.hpp"

namespace tpkit {

struct VerdictOptions {
  double min_log10_odds = 3;  // accept when -log10(NFA) reaches this
  long hypotheses = 1;        // how many maps the search evaluated (the NFA's number of tests)
  ClusterModel model = ClusterModel::Homography;  // the map's model: its s minimal points replace the 4 below
  double domain_area_b = 0;   // px^2: the field B's points come from (its image, w x h), when known and
                              // larger than hull B; 0: hull B
};

struct Verdict {
  bool accepted = false;
  std::string degenerate;   // why h is degenerate, "" if it is not
  std::string undetermined; // why the points cannot verify any h (4 or fewer of A mapped into B), "" otherwise
  int inliers = 0;          // k at the chosen radius
  int candidates = 0;       // n: the trials, every point of A
  int mapped_into_b = 0;    // points of A mapped into hull B (or within kCandidateMargin s of it)
  double radius_px = 0;     // the radius of the best significance
  double expected = 0;      // chance inliers at that radius: 4 + (n - 4) p
  double log10_odds = 0;    // -log10(NFA); -inf for a degenerate h
};

constexpr double kMinAreaRatio = 1e-3;
constexpr double kCandidateMargin = 0.25;

// The a contrario significance of a set of matches (the verdict's statistic, also used on parts of the
// clusters): n candidates, their match distances (any order; sorted here), `density` = points of B per
// square pixel, `spacing` = B's mean point spacing (for the radius floor), `fitted` = the minimal points
// of the model (4 for a homography: the 4 above; s in general). log10_tail = log10 min_k P_k
// (<= 0), radii = max(1, n - fitted), the number of radii tried.
struct Significance {
  double log10_tail = 0;
  int inliers = 0;
  double radius = 0, p = 0;
  int radii = 1;
};
Significance match_significance(int n, std::vector<double> distances, double density, double spacing, int fitted = 4);

// log10 of the binomial upper tail P(K >= k), K ~ Bin(n, p); 0 for k <= 0, -inf for k > n.
double log10_binomial_tail(int n, int k, double p);

// "" when H is a usable map between the clusters, else the reason (line at infinity across a cluster,
// a cluster collapsed). MapCheck keeps the clusters' hulls for many maps (the search's hypotheses).
class MapCheck {
 public:
  MapCheck(const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B);
  std::string operator()(const Eigen::Matrix3d& H) const;
  const std::vector<Eigen::Vector2d>& hull_b() const { return hull_b_; }  // counter-clockwise
  double area_b() const { return area_b_; }
  double outside_b(const Eigen::Vector2d& q) const;  // distance from hull B, 0 inside

 private:
  std::vector<Eigen::Vector2d> hull_a_, hull_b_;
  double area_a_ = 0, area_b_ = 0;
};
std::string degeneracy(const Eigen::Matrix3d& H, const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B);

Verdict judge_homography(const ClusterCost& cost, const Eigen::Matrix3d& H, const VerdictOptions& opt = {});

// The same statistic on the points of A within `radius` of `center` (image 1 pixels) alone, as
// log10 odds over its own radii only (no count of hypotheses): how far a hypothesis refined on a
// region is supported there. The region-growing refinement (cluster_optimize.hpp) drops hypotheses
// whose regions stay at chance level. -inf for a degenerate H.
class RegionSupport {
 public:
  explicit RegionSupport(const ClusterCost& cost);
  double log10_odds(const Eigen::Matrix3d& H, const Eigen::Vector2d& center, double radius) const;

 private:
  const ClusterCost& cost_;
  MapCheck check_;
  double density_, spacing_;
};

}  // namespace tpkit
