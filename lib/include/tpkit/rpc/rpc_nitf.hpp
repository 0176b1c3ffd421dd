// The RPC model of a NITF image: the RPC00B TRE (STDI-0002 vol. 1 appendix E; RPC00A, the older term
// order, remapped to RPC00B's as GDAL does) of its first image segment, read and written.
//
// The TRE is 1041 characters of fixed-width fields: offsets and scales in whole pixels and metres and
// 1e-4 degree, ERR_BIAS / ERR_RAND in metres (0 when unknown), coefficients with 7 significant digits (+d.ddddddE+d). Its pixel
// convention is tpkit's ((0, 0) the centre of the top-left pixel), so no offset is converted. A model
// whose offsets and scales are not representable (Pléiades: LINE_OFF 18339.5) is written renormalized
// (renormalized_rpc: the same function under the rounded offsets, the scales rounded outward) and then its
// coefficients rounded: what that changes is measured over the validity volume and returned.
#pragma once
#include <optional>
#include <string>

#include "tpkit/core/nitf_image.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

// The model in an RPC00B or RPC00A TRE. InputError(path: RPC00B: reason) for a short TRE, a field that
// is not a number in its field's form (digits; a sign, a decimal point, an exponent only where the
// field's form has one: no "0x00fa", no "+" before LINE_OFF, no blank inside), or SUCCESS = 0 (the
// producer says the model is not valid).
RpcModel parse_rpc_tre(const NitfTre& tre, const std::string& path);

// The model of a NITF image (RPC00B, else RPC00A); nothing when it has neither. A second TRE of the tag
// is accepted when it repeats the first byte for byte, and refused (naming both) when it differs.
std::optional<RpcModel> read_rpc_nitf(const NitfImage& image);

// The RPC00B TRE of a model, the model it holds (what a reader gets back) and the largest difference of
// their projections over the validity volume (a 21 x 21 x 5 grid), pixels. InputError when the model
// does not fit the fields (offsets beyond 999999 / 99999 pixels, a scale of 0, a coefficient >= 1e10).
struct RpcTre {
  NitfTre tre;
  RpcModel model;
  double max_change_px = 0;
};
RpcTre format_rpc00b_tre(const RpcModel& m);

}  // namespace tpkit
