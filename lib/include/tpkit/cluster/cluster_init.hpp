// The --init file of cluster-homog: starting values of the physical parameters (physical_homography.hpp)
// as "key = value" lines ('#' starts a comment). Keys, with N = 1 or 2 for the image:
//   pxN pyN (m)  rhoN (m)  alphaN betaN gammaN thetaN (rad)  resN (m/pixel)  cxN cyN (pixels)
// or, instead of pxN pyN rhoN alphaN betaN, geodetic positions (WGS84, degrees and metres above the
// ellipsoid):
//   satN_lat satN_lon satN_h       satellite position
//   sceneN_lat sceneN_lon sceneN_h target point (scene centre)
//   origin_lat origin_lon origin_h ground frame origin (optional; default: scene1)
// Then, with GeographicLib::LocalCartesian at the scene centre (x east, y north, z up):
//   rhoN = |S|, alphaN = atan2(S_north, S_east), betaN = asin(S_up / rhoN)
// and (pxN, pyN) = east and north of the scene centre in the LocalCartesian frame at the origin
// (its height is ignored: the ground is the plane z = 0).
// Or a homography start: h11 h12 h13 h21 h22 h23 h31 h32 h33 (x_B ~ H x_A, pixels).
// Defaults: gammaN = thetaN = cxN = cyN = 0 and pxN = pyN = 0. resN is required with physical values.
// Errors (InputError with file:line): unknown or repeated keys, values that are not finite numbers,
// impossible angles (elevation outside (0, pi/2], satellite below the horizon), rho <= 0, res <= 0,
// latitudes outside [-90, 90].
#pragma once
#include <Eigen/Core>
#include <istream>
#include <string>

#include "tpkit/cluster/physical_homography.hpp"

namespace tpkit {

struct ClusterInit {
  bool has_physical = false;
  PhysicalParams physical;
  bool has_H = false;
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
};

ClusterInit read_cluster_init(std::istream& in, const std::string& source);
ClusterInit read_cluster_init_file(const std::string& path);

// Azimuth (rad, from east towards north), elevation (rad) and distance (m) of a satellite seen from a
// ground point, both geodetic (degrees, metres above the WGS84 ellipsoid).
struct LookAngles {
  double alpha, beta, rho;
};
LookAngles look_angles(double sat_lat, double sat_lon, double sat_h, double lat, double lon, double h);

}  // namespace tpkit
