// The figures of an RPC adjustment (rpc-adjust's residuals.svg), drawn with the plotting module
// (core/svg_plot.hpp) from an AdjustResult.
#pragma once
#include <string>
#include <vector>

#include "tpkit/rpc/rpc_adjust.hpp"

namespace tpkit {

// Figure: per image, the residual vectors at the observed points before (zero bias) and after the
// adjustment, exaggerated by one common factor (scale bar), over the image extent.
void plot_rpc_residuals(const std::string& path, const std::vector<AdjustImage>& images, const AdjustResult& r,
                        const std::string& title);

}  // namespace tpkit
