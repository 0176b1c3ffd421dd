#include "tpkit/rpc/rpc_ground.hpp"

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/UTMUPS.hpp>

#include <Eigen/Dense>
#include <cmath>

#include "tpkit/core/error.hpp"
#include "tpkit/core/text_table.hpp"

namespace tpkit {

Eigen::Vector2d rpc_observe(const RpcObservation& o, const Eigen::Vector3d& llh, Eigen::Matrix<double, 2, 3>* J) {
  Eigen::Matrix<double, 2, 3> Jp;
  Eigen::Vector2d p = o.model->project(llh, Jp);
  if (!o.bias) {
    if (J) *J = Jp;
    return p;
  }
  if (J) {
    Eigen::Matrix2d D;
    D << 1 + o.bias->a[1], o.bias->a[2], o.bias->b[1], 1 + o.bias->b[2];
    *J = D * Jp;
  }
  return o.bias->apply(p);
}

namespace {
double cost_of(const std::vector<RpcObservation>& v, const Eigen::Vector3d& g) {
  double s = 0;
  for (const auto& o : v) s += (rpc_observe(o, g) - o.xy).squaredNorm();
  return s;
}

// Start: the point of view 1 at h_start, moved along its ray to the height that best fits view 2.
Eigen::Vector3d start_point(const std::vector<RpcObservation>& v, double h0) {
  const RpcModel& m = *v[0].model;
  Eigen::Vector2d x0 = v[0].xy;
  if (v[0].bias) x0 -= v[0].bias->offset(x0);
  auto at = [&](double h) {
    Eigen::Vector2d ll = m.localize(x0[0], x0[1], h);
    return Eigen::Vector3d(ll[0], ll[1], h);
  };
  Eigen::Vector3d g0 = at(h0), g1 = at(h0 + 0.25 * m.height_scale);
  // view 2's residual is nearly linear in h along the ray: one secant step
  Eigen::Vector2d r0 = rpc_observe(v[1], g0) - v[1].xy, r1 = rpc_observe(v[1], g1) - v[1].xy;
  Eigen::Vector2d d = r1 - r0;
  if (d.squaredNorm() <= 0) return g0;
  double t = -r0.dot(d) / d.squaredNorm();
  t = std::max(-8.0, std::min(8.0, t));
  return at(h0 + t * 0.25 * m.height_scale);
}
}  // namespace

double height_sigma_unit(const std::vector<RpcObservation>& v, const Eigen::Vector3d& g) {
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  for (const auto& o : v) {
    Eigen::Matrix<double, 2, 3> J;
    rpc_observe(o, g, &J);
    N += J.transpose() * J;
  }
  Eigen::Vector3d s = N.diagonal().cwiseSqrt().cwiseMax(1e-300).cwiseInverse();
  Eigen::Matrix3d C = s.asDiagonal() * (s.asDiagonal() * N * s.asDiagonal()).inverse() * s.asDiagonal();
  return std::sqrt(std::max(C(2, 2), 0.0));
}

RpcIntersection intersect_rpc(const std::vector<RpcObservation>& v, double h_start) {
  RpcIntersection out;
  if (v.size() < 2) throw NumericalError("a ground point needs at least two views");
  if (!std::isfinite(h_start)) h_start = v[0].model->height_off;
  Eigen::Vector3d g;
  try {
    g = start_point(v, h_start);
  } catch (const NumericalError&) {
    return out;
  }
  double cost = cost_of(v, g);
  Eigen::Matrix3d N;
  for (int it = 0; it < 30; ++it) {
    N.setZero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (const auto& o : v) {
      Eigen::Matrix<double, 2, 3> J;
      Eigen::Vector2d r = rpc_observe(o, g, &J) - o.xy;
      N += J.transpose() * J;
      rhs -= J.transpose() * r;
    }
    // scale the columns (degrees vs metres) before solving
    Eigen::Vector3d s = N.diagonal().cwiseSqrt().cwiseMax(1e-300).cwiseInverse();
    Eigen::Matrix3d Ns = s.asDiagonal() * N * s.asDiagonal();
    Eigen::Vector3d step = s.asDiagonal() * Ns.ldlt().solve(s.asDiagonal() * rhs);
    if (!step.allFinite()) return out;
    double lambda = 1;
    bool improved = false;
    for (int k = 0; k < 10; ++k, lambda *= 0.5) {
      Eigen::Vector3d trial = g + lambda * step;
      double c = cost_of(v, trial);
      if (c <= cost) {
        improved = c < cost;
        g = trial;
        cost = c;
        break;
      }
    }
    if (!improved || std::fabs(step[2]) * lambda < 1e-7) break;
  }
  out.llh = g;
  out.rms_px = std::sqrt(cost / v.size());
  out.sigma_h1 = height_sigma_unit(v, g);
  out.ok = g.allFinite() && std::isfinite(out.sigma_h1);
  return out;
}

GroundCrs parse_ground_crs(const std::string& s) {
  if (s == "geographic") return GroundCrs::geographic;
  if (s == "utm") return GroundCrs::utm;
  if (s == "ecef") return GroundCrs::ecef;
  throw UsageError("--crs: expected geographic, utm or ecef, got '" + s + "'");
}

GroundConverter::GroundConverter(GroundCrs crs, double lon0, double lat0) : crs_(crs) {
  if (crs_ == GroundCrs::utm) {
    zone_ = GeographicLib::UTMUPS::StandardZone(lat0, lon0);
    north_ = lat0 >= 0;
    if (zone_ == GeographicLib::UTMUPS::UPS) throw UsageError("--crs utm: the scene is in the polar (UPS) zone");
  }
}

Eigen::Vector3d GroundConverter::operator()(const Eigen::Vector3d& llh) const {
  switch (crs_) {
    case GroundCrs::geographic: return llh;
    case GroundCrs::utm: {
      int zone;
      bool north;
      double e, n;
      GeographicLib::UTMUPS::Forward(llh[1], llh[0], zone, north, e, n, zone_);
      if (north != north_) n += north_ ? -GeographicLib::UTMUPS::UTMShift() : GeographicLib::UTMUPS::UTMShift();
      return {e, n, llh[2]};
    }
    case GroundCrs::ecef: {
      double X, Y, Z;
      GeographicLib::Geocentric::WGS84().Forward(llh[1], llh[0], llh[2], X, Y, Z);
      return {X, Y, Z};
    }
  }
  return llh;
}

Eigen::Vector3d GroundConverter::checked(const Eigen::Vector3d& llh) const {
  try {
    return (*this)(llh);
  } catch (const GeographicLib::GeographicErr& e) {
    throw NumericalError("lon " + format_figure(llh[0], 9) + ", lat " + format_figure(llh[1], 9) + ": not in " + description() +
                         ": " + e.what());
  }
}

Eigen::Vector3d GroundConverter::operator()(const Eigen::Vector3d& llh, long long track) const {
  try {
    return checked(llh);
  } catch (const NumericalError& e) {
    throw NumericalError("track " + std::to_string(track) + " at " + e.what());
  }
}

Eigen::Vector3d GroundConverter::inverse(const Eigen::Vector3d& p) const {
  try {
    switch (crs_) {
      case GroundCrs::geographic: return p;
      case GroundCrs::utm: {
        double lat, lon;
        GeographicLib::UTMUPS::Reverse(zone_, north_, p[0], p[1], lat, lon);
        return {lon, lat, p[2]};
      }
      case GroundCrs::ecef: {
        double lat, lon, h;
        GeographicLib::Geocentric::WGS84().Reverse(p[0], p[1], p[2], lat, lon, h);
        return {lon, lat, h};
      }
    }
  } catch (const GeographicLib::GeographicErr& e) {
    throw NumericalError("not in " + description() + ": " + e.what());
  }
  return p;
}

std::vector<std::string> GroundConverter::columns() const {
  switch (crs_) {
    case GroundCrs::geographic: return {"lon", "lat", "h"};
    case GroundCrs::utm: return {"easting", "northing", "h"};
    case GroundCrs::ecef: return {"X", "Y", "Z"};
  }
  return {};
}

int GroundConverter::epsg() const {
  switch (crs_) {
    case GroundCrs::geographic: return 4979;
    case GroundCrs::utm: return (north_ ? 32600 : 32700) + zone_;
    case GroundCrs::ecef: return 4978;
  }
  return 0;
}

std::string GroundConverter::description() const {
  switch (crs_) {
    case GroundCrs::geographic:
      return "EPSG:4979 (WGS 84 geographic 3D: lon lat in degrees, h in metres above the ellipsoid)";
    case GroundCrs::utm:
      return "EPSG:" + std::to_string((north_ ? 32600 : 32700) + zone_) + " (WGS 84 / UTM zone " +
             std::to_string(zone_) + (north_ ? "N" : "S") + ": easting northing in metres) + h in metres above the ellipsoid";
    case GroundCrs::ecef: return "EPSG:4978 (WGS 84 geocentric: X Y Z in metres)";
  }
  return "";
}

}  // namespace tpkit
