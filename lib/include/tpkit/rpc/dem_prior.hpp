// The height prior of an adjustment (rpc_adjust.hpp HeightPrior) and the ground of a localization from a
// reference DEM in any CRS and vertical datum (ground/reference_dem.hpp): heights above the WGS 84 ellipsoid,
// bilinear, with their gradient in m per degree of lon and lat; unknown off the DEM and on its voids.
#pragma once
#include <memory>

#include "tpkit/ground/reference_dem.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"

namespace tpkit {

// `dem` is shared by the prior (read from any thread: ReferenceDem serializes its reads).
HeightPrior reference_dem_prior(std::shared_ptr<const ReferenceDem> dem, double sigma);

}  // namespace tpkit
