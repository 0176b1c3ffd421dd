#include "tpkit/synth/synth_rpc.hpp"

#include <GeographicLib/LocalCartesian.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/synth/synth_scene.hpp"
#include "tpkit/synth/synth_structures.hpp"

namespace tpkit {

SynthGeoOrigin parse_geo_origin(const std::string& text, const std::string& option) {
  std::vector<double> v = parse_number_list(text, option, "LAT,LON,H");
  if (v.size() != 3) throw UsageError(option + ": expected LAT,LON,H (degrees, degrees, metres), got '" + text + "'");
  if (std::fabs(v[0]) > 80) throw UsageError(option + ": latitude must be within [-80, 80] degrees, got '" + text + "'");
  if (std::fabs(v[1]) > 180) throw UsageError(option + ": longitude must be within [-180, 180] degrees, got '" + text + "'");
  return {v[0], v[1], v[2]};
}

struct SynthGeoFrame::Impl {
  SynthGeoOrigin origin;
  GeographicLib::LocalCartesian lc;
  double half = 0;  // S / 2
};

SynthGeoFrame::SynthGeoFrame(const SynthScene& scene, const SynthGeoOrigin& o) : impl_(new Impl) {
  impl_->origin = o;
  impl_->lc = GeographicLib::LocalCartesian(o.lat, o.lon, o.h, GeographicLib::Geocentric::WGS84());
  impl_->half = 0.5 * scene.scene_size();
}
SynthGeoFrame::~SynthGeoFrame() = default;
SynthGeoFrame::SynthGeoFrame(SynthGeoFrame&&) noexcept = default;

const SynthGeoOrigin& SynthGeoFrame::origin() const { return impl_->origin; }

Eigen::Vector3d SynthGeoFrame::to_llh(const Eigen::Vector3d& X) const {
  double lat, lon, h;
  impl_->lc.Reverse(X[0] - impl_->half, X[1] - impl_->half, X[2], lat, lon, h);
  return {lon, lat, h};
}

Eigen::Vector3d SynthGeoFrame::from_llh(const Eigen::Vector3d& llh) const {
  double x, y, z;
  impl_->lc.Forward(llh[1], llh[0], llh[2], x, y, z);
  return {x + impl_->half, y + impl_->half, z};
}

RpcFit synth_view_rpc(const SynthScene& scene, const SynthGeoFrame& geo, int view, const ImageBias& bias) {
  // heights: the relief, and the roofs and crowns of a scene with structures, with 10 m to spare
  const double S = scene.scene_size(),
               r = std::max(0.5 * scene.params().relief, scene.has_structures() ? scene.structures().zmax() : 0.0) + 10;
  RpcFitVolume v;
  v.lon0 = v.lat0 = INFINITY;
  v.lon1 = v.lat1 = -INFINITY;
  auto extend = [&](double X, double Y) {
    Eigen::Vector3d g = geo.to_llh({X, Y, 0});
    v.lon0 = std::min(v.lon0, g[0]);
    v.lon1 = std::max(v.lon1, g[0]);
    v.lat0 = std::min(v.lat0, g[1]);
    v.lat1 = std::max(v.lat1, g[1]);
  };
  if (!scene.is_block()) {
    for (double X : {0.0, S})
      for (double Y : {0.0, S}) extend(X, Y);
  } else {
    // a block's view sees part of the scene square: its footprint at heights -r and r
    for (double Z : {-r, r})
      for (const Eigen::Vector2d& c : scene.footprint(view, Z)) extend(c.x(), c.y());
  }
  v.h0 = geo.origin().h - r;
  v.h1 = geo.origin().h + r;
  // model = (I + d)^-1 o truth: p = c + (I + A) q  =>  q = (I + A)^-1 (p - c)
  Eigen::Matrix2d IA;
  IA << 1 + bias.a[1], bias.a[2], bias.b[1], 1 + bias.b[2];
  const Eigen::Matrix2d inv = IA.inverse();
  const Eigen::Vector2d c(bias.a[0], bias.b[0]);
  return fit_rpc([&](const Eigen::Vector3d& llh) { return Eigen::Vector2d(inv * (scene.project(view, geo.from_llh(llh)) - c)); },
                 v);
}

GeoGrid synth_dem(const SynthScene& scene, const SynthGeoFrame& geo, double spacing) {
  const double S = scene.scene_size();
  Eigen::Vector3d sw = geo.to_llh({0, 0, 0}), ne = geo.to_llh({S, S, 0}), e1 = geo.to_llh({spacing, 0, 0}),
                  n1 = geo.to_llh({0, spacing, 0});
  GeoGrid g;
  g.dlon = e1[0] - sw[0];
  g.dlat = n1[1] - sw[1];
  g.lon0 = sw[0];
  g.lat0 = ne[1];
  g.width = static_cast<long>(std::ceil((ne[0] - sw[0]) / g.dlon)) + 1;
  g.height = static_cast<long>(std::ceil((ne[1] - sw[1]) / g.dlat)) + 1;
  g.data.resize(static_cast<size_t>(g.width * g.height));
  const double h0 = geo.origin().h;
  for (long j = 0; j < g.height; ++j)
    for (long i = 0; i < g.width; ++i) {
      Eigen::Vector3d llh(g.lon0 + i * g.dlon, g.lat0 - j * g.dlat, h0);
      // the terrain point below (lon, lat): two fixed-point steps on its height (the local vertical and the
      // ellipsoid normal differ by millimetres over the scene)
      Eigen::Vector3d X = geo.from_llh(llh);
      for (int k = 0; k < 2; ++k) {
        X[2] = scene.height(X[0], X[1]);
        Eigen::Vector3d back = geo.to_llh(X);
        llh[2] = back[2];
        X = geo.from_llh(Eigen::Vector3d(g.lon0 + i * g.dlon, g.lat0 - j * g.dlat, llh[2]));
      }
      g.data[static_cast<size_t>(j * g.width + i)] = static_cast<float>(llh[2]);
    }
  return g;
}

std::pair<int, ImageBias> parse_view_bias(const std::string& text, int views) {
  size_t colon = text.find(':');
  if (colon == std::string::npos) throw UsageError("--rpc-bias: expected VIEW:dx,dy[,dxy,dyy[,dxx,dyx]], got '" + text + "'");
  std::string vs = text.substr(0, colon);
  const bool digits = !vs.empty() && vs.size() <= 3 && vs.find_first_not_of("0123456789") == std::string::npos && vs[0] != '0';
  const int view = digits ? std::stoi(vs) : 0;
  if (view < 1 || view > views) {
    if (views == 3) throw UsageError("--rpc-bias: the view must be 1, 2 or 3, got '" + vs + "'");
    throw UsageError("--rpc-bias: the view must be between 1 and " + std::to_string(views) + ", got '" + vs + "'");
  }
  return {view - 1, parse_image_bias(text.substr(colon + 1), "--rpc-bias")};
}

}  // namespace tpkit
