// Cost profiles (Navy et al. 2005, figures 2 and 5) and cluster-homog's extra outputs.
//
// A scan varies one parameter linearly from lo to hi in `steps` values, all others fixed, and
// evaluates the cluster cost (cluster_cost.hpp) of each homography x_B ~ H x_A:
//   math      parameters h11 ... h33 of H scaled so that h33 = 1 (absolute values)
//   physical  parameters px1 ... cy2 of physical_homography.hpp (absolute values, metres / radians /
//             m per pixel / pixels)
// Files (text tables of text_table.hpp, documented in man/cluster-homog.1):
//   "# tpkit scan 1"   columns value cost           (cost in pixels; "# parameter: NAME")
//   "# tpkit pairs 1"  columns x1 y1 x2 y2 d        mutual nearest neighbours under H: A point
//                       (image 1 pixels), B point (image 2 pixels), d = |h(A) - B| in image-2 pixels
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "tpkit/cluster/cluster_cost.hpp"
#include "tpkit/cluster/physical_homography.hpp"
#include "tpkit/core/text_table.hpp"

namespace tpkit {

struct ScanRow {
  double value, cost;
};

// Physical scan when `param` names a physical parameter (needs phys), math scan for h11 ... h33.
// Throws UsageError for an unknown name, steps < 2 or lo >= hi. Values where H is singular are left out.
// The most values one scan takes (--steps).
constexpr int kMaxScanSteps = 100000;
// Throws UsageError naming the option unless PARAM is a scan parameter (h11..h33 or a physical name),
// LO < HI both finite and 2 <= STEPS <= kMaxScanSteps. Tools call it before any work.
void check_scan(const std::string& param, double lo, double hi, int steps);

std::vector<ScanRow> scan_cost(const ClusterCost& cost, const std::string& param, const Eigen::Matrix3d& H,
                               const PhysicalParams* phys, double lo, double hi, int steps);

void save_scan(const std::string& path, const std::vector<ScanRow>& rows, const std::string& param,
               const std::vector<ImageRef>& images, Meta meta);
// SVG figure of the scan (cost in pixels against the parameter).
void plot_scan(const std::string& path, const std::vector<ScanRow>& rows, const std::string& param,
               const std::string& title);

// The two clusters before and after (the paper's figure 6), in image-2 pixels: cluster B, and cluster A
// carried by H_before (left panel) and by H_after (right panel). The title of each panel gives its cost.
void plot_clusters(const std::string& path, const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B,
                   const Eigen::Matrix3d& H_before, double cost_before, const Eigen::Matrix3d& H_after,
                   double cost_after);

void save_pairs(const std::string& path, const ClusterCost& cost, const std::vector<MutualPair>& pairs,
                const std::vector<ImageRef>& images, const Meta& meta);

}  // namespace tpkit
