// Ground points from RPC cameras: least-squares intersection of a track's views, and the coordinate
// systems the tools write them in (GeographicLib: UTMUPS, Geocentric).
//
// Ground: (lon, lat) degrees WGS84, h metres above the WGS84 ellipsoid. Pixels: tpkit (x column, y row,
// (0, 0) the centre of the top-left pixel). Residual = projected (with the view's bias) minus observed.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

#include "tpkit/rpc/rpc_bias.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

// One view of a track: its camera (and optional image-space bias) and the observed pixel.
struct RpcObservation {
  const RpcModel* model = nullptr;
  const ImageBias* bias = nullptr;  // none: the plain model
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
};

// Projection of g by the observation's camera (bias applied), with its Jacobian when J is not null.
Eigen::Vector2d rpc_observe(const RpcObservation& o, const Eigen::Vector3d& llh, Eigen::Matrix<double, 2, 3>* J = nullptr);

struct RpcIntersection {
  Eigen::Vector3d llh = Eigen::Vector3d::Zero();
  double rms_px = 0;     // sqrt(mean over the views of |residual|^2)
  double sigma_h1 = 0;   // standard deviation of h (m) for image noise of 1 px per coordinate
  bool ok = false;       // converged, with finite geometry
};

// Standard deviation of h (m) at g for image noise of 1 px per coordinate: sqrt of (J^T J)^-1 (h, h).
double height_sigma_unit(const std::vector<RpcObservation>& views, const Eigen::Vector3d& g);

// Gauss-Newton over all views (>= 2), started from the first view's localization at `h_start`
// (default: its model's height offset) and its intersection with the second view.
RpcIntersection intersect_rpc(const std::vector<RpcObservation>& views, double h_start = NAN);

// Output coordinate systems.
enum class GroundCrs { geographic, utm, ecef };
// "geographic" | "utm" | "ecef"; UsageError otherwise.
GroundCrs parse_ground_crs(const std::string&);

// Converts (lon, lat, h) to the output system; UTM: the zone of the reference point (lon0, lat0) is used
// for every point (a file is in one zone).
class GroundConverter {
 public:
  GroundConverter(GroundCrs crs, double lon0, double lat0);
  Eigen::Vector3d operator()(const Eigen::Vector3d& llh) const;
  // The same; NumericalError naming the track for a point the system cannot hold (UTM: too far from the
  // zone; GeographicLib's own message follows).
  Eigen::Vector3d operator()(const Eigen::Vector3d& llh, long long track) const;
  // The same, the NumericalError naming the point only.
  Eigen::Vector3d checked(const Eigen::Vector3d& llh) const;
  // The inverse: a point of the output system back to (lon, lat, h); NumericalError for one the system
  // cannot hold (UTM: an easting or northing outside the zone's range).
  Eigen::Vector3d inverse(const Eigen::Vector3d& xyz) const;
  // Column names of the three coordinates: lon lat h | easting northing h | X Y Z.
  std::vector<std::string> columns() const;
  // The "# crs:" value, e.g. "EPSG:4979 (WGS 84 geographic 3D: lon lat degrees, h metres above the ellipsoid)".
  std::string description() const;
  GroundCrs crs() const { return crs_; }
  // UTM: the zone (1..60) and hemisphere of every point of the file; 0 and true otherwise.
  int zone() const { return zone_; }
  bool north() const { return north_; }
  // The EPSG code of the output system: 4979, 32600 + zone (north) or 32700 + zone (south), 4978.
  int epsg() const;

 private:
  GroundCrs crs_;
  int zone_ = 0;
  bool north_ = true;
};

}  // namespace tpkit
