// A ground translation folded into an RPC model, exactly: the model M' with M'(P + s) = M(P) for every ground
// point P, s = (east, north, up) m of a GroundShift (ground/dem_align.hpp) converted to degrees at its centre
// (lon0, lat0). Only the offsets change: LON_OFF += s_lon, LAT_OFF += s_lat, HEIGHT_OFF += s_up, since the
// model reads (lon - LON_OFF) / LON_SCALE etc. (The degree conversion is that of the centre: over a scene of
// 20 km the east metres of a shift of 10 m differ by below 1 mm from one edge to the other.)
#pragma once
#include "tpkit/ground/dem_align.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

RpcModel shift_rpc_on_ground(const RpcModel& model, const GroundShift& shift);

}  // namespace tpkit
