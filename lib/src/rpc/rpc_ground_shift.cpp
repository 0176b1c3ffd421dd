#include "tpkit/rpc/rpc_ground_shift.hpp"

namespace tpkit {

RpcModel shift_rpc_on_ground(const RpcModel& model, const GroundShift& shift) {
  RpcModel m = model;
  m.lon_off += shift.dlon();
  m.lat_off += shift.dlat();
  m.height_off += shift.up;
  return m;
}

}  // namespace tpkit
