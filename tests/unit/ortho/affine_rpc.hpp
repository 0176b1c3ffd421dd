// The ortho tests' RPC model, affine in (lon, lat, h) by construction: x = 200 + 200 L + 20 H,
// y = 200 - 200 P (L, P, H the normalized lon, lat, h): a 400 x 400 image over 0.004 deg of longitude and
// latitude (about 320 x 440 m at 43.3 N), 20 px of parallax per height scale (0.1 px per metre).
#pragma once
#include "tpkit/rpc/rpc_model.hpp"

inline tpkit::RpcModel affine_rpc(double lon_off) {
  tpkit::RpcModel m;
  m.lon_off = lon_off;
  m.lat_off = 43.3;
  m.height_off = 100;
  m.lon_scale = m.lat_scale = 0.002;
  m.height_scale = 200;
  m.samp_off = m.line_off = 200;
  m.samp_scale = m.line_scale = 200;
  m.samp_num[1] = 1;
  m.samp_num[3] = 0.1;
  m.line_num[2] = -1;
  m.samp_den[0] = m.line_den[0] = 1;
  return m;
}
