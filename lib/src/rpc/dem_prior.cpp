#include "tpkit/rpc/dem_prior.hpp"

namespace tpkit {

HeightPrior reference_dem_prior(std::shared_ptr<const ReferenceDem> dem, double sigma) {
  HeightPrior p;
  p.sigma = sigma;
  p.at = [dem = std::move(dem)](double lon, double lat, double& h, double* grad) { return dem->height(lon, lat, h, grad); };
  return p;
}

}  // namespace tpkit
