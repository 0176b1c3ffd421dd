// RPC cameras of the synthetic triplet or block (tp-synth): the scene's local frame placed on the WGS84 ellipsoid,
// and an RPC00B per view fitted to its camera over the scene volume (terrain-independent fit on a 3-D grid,
// as vendors do), optionally perturbed by a known image-space bias.
//
// Geographic frame: the scene centre (X, Y, Z) = (S/2, S/2, 0) (S = scene_size()) is the point (lat, lon, h)
// of `origin`; X east, Y north, Z up are the axes of GeographicLib's LocalCartesian there (ENU, metres).
// Bias convention (rpc_bias.hpp): the model written for a view with bias d satisfies
// truth(g) = d applied to model(g), i.e. model = (I + d)^-1 o truth: d is what rpc-adjust must recover.
#pragma once
#include <Eigen/Core>
#include <array>
#include <map>
#include <memory>
#include <string>

#include "tpkit/rpc/rpc_bias.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

class SynthScene;

struct SynthGeoOrigin {
  double lat = 43.3, lon = 5.4, h = 100;  // Marseille, metres above the ellipsoid
};
// "LAT,LON,H" (degrees, degrees, metres); UsageError naming `option` otherwise.
SynthGeoOrigin parse_geo_origin(const std::string& text, const std::string& option);

class SynthGeoFrame {
 public:
  SynthGeoFrame(const SynthScene& scene, const SynthGeoOrigin& origin);
  ~SynthGeoFrame();
  SynthGeoFrame(SynthGeoFrame&&) noexcept;
  Eigen::Vector3d to_llh(const Eigen::Vector3d& X) const;    // local (m) -> lon, lat (deg), h (m)
  Eigen::Vector3d from_llh(const Eigen::Vector3d& llh) const;
  const SynthGeoOrigin& origin() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The RPC00B of `view` (0-based) with bias d (none: zero): fitted on the scene square (a block: the view's
// footprint at heights -+(relief/2 + 10)) x [-relief/2 - 10, relief/2 + 10] m about the origin height. fit.rms_px / max_px: against the biased camera on the check grid.
RpcFit synth_view_rpc(const SynthScene& scene, const SynthGeoFrame& geo, int view, const ImageBias& bias = {});

// The terrain as a DEM on a geographic grid of about `spacing` metres covering the scene square: heights above
// the ellipsoid of the terrain point below each (lon, lat) sample (image_io.hpp GeoGrid, truth.dem.tif).
struct GeoGrid;
GeoGrid synth_dem(const SynthScene& scene, const SynthGeoFrame& geo, double spacing);

// "VIEW:dx,dy[,dxy,dyy[,dxx,dyx]]" (VIEW 1..views) -> view index (0-based) and bias; UsageError otherwise.
std::pair<int, ImageBias> parse_view_bias(const std::string& text, int views = 3);

}  // namespace tpkit
