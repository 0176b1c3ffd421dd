// The figures of an RPC adjustment (rpc-adjust's residuals.svg), drawn with the plotting module
// (core/svg_plot.hpp) from an AdjustResult.
#pragma once
#include <string>
#include <vector>

#include "tpkit/rpc/rpc_adjust.hpp"

namespace tpkit {

// Figure: per image, the residual field (core/residual_field.hpp) before (zero bias) and after the
// adjustment, one above the other, one exaggeration and colour scale for every panel, RMSE, median and
// p90 above each panel; the bias model's field drawn over the "before" panels.
void plot_rpc_residuals(const std::string& path, const std::vector<AdjustImage>& images, const AdjustResult& r,
                        const std::string& title);

}  // namespace tpkit
