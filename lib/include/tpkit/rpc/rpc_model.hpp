// The rational polynomial camera model RPC00B (NITF STDI-0002 / GeoTIFF tag 50844), and what is computed
// with it: project, localize, the epipolar curve of a pixel in another image, and the terrain-independent
// fit of an RPC00B to any ground-to-image function over a volume (as vendors make them).
//
// Conventions. Ground: longitude, latitude in degrees (WGS84), height h in metres above the WGS84
// ellipsoid. Image: tpkit pixels, x = column (RPC "sample"), y = row (RPC "line"), (0, 0) = the centre of
// the top-left pixel. RPC00B uses the same pixel convention (GDAL, alg/gdal_rpc.cpp: "RPCs are using the
// center of upper left pixel = 0,0 convention"), so the GeoTIFF tag, the .RPB and the _rpc.txt forms are
// taken as they are; DIMAP (1-based) is converted where it is read and written (rpc_io.cpp) only.
// Each of the four rational functions is a cubic polynomial in the normalized ground coordinates
// (L, P, H) = ((lon - lon_off) / lon_scale, (lat - lat_off) / lat_scale, (h - height_off) / height_scale)
// with the RPC00B term order 1 L P H LP LH PH L2 P2 H2 PLH L3 LP2 LH2 L2P P3 PH2 L2H P2H H3, and
// x = samp_num / samp_den * samp_scale + samp_off, y = line_num / line_den * line_scale + line_off.
// The optional direct model (DIMAP's image -> ground) uses the same term order in the normalized image
// coordinates (sample, line, height) in the place of (L, P, H).
#pragma once
#include <Eigen/Core>
#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace tpkit {

using RpcPoly = std::array<double, 20>;

// The 20 RPC00B monomials of normalized (L, P, H), in order; templated so that automatic
// differentiation (Ceres jets) goes through it.
template <typename T>
void rpc_terms(const T& L, const T& P, const T& H, T* t) {
  t[0] = T(1.0);
  t[1] = L;
  t[2] = P;
  t[3] = H;
  t[4] = L * P;
  t[5] = L * H;
  t[6] = P * H;
  t[7] = L * L;
  t[8] = P * P;
  t[9] = H * H;
  t[10] = P * L * H;
  t[11] = L * L * L;
  t[12] = L * P * P;
  t[13] = L * H * H;
  t[14] = L * L * P;
  t[15] = P * P * P;
  t[16] = P * H * H;
  t[17] = L * L * H;
  t[18] = P * P * H;
  t[19] = H * H * H;
}

template <typename T>
T rpc_eval(const RpcPoly& c, const T* t) {
  T s = T(0.0);
  for (int i = 0; i < 20; ++i) s += c[i] * t[i];
  return s;
}

// How far outside its validity box (normalized coordinates, +-1) a model is still evaluated
// (RpcModel::outside_domain): 10 scales. The box is the image's footprint and its scene's height range (a
// scale is half of each: kilometres for a full WorldView or Pleiades scene, hundreds of metres for a crop);
// 10 scales off the centre is 4.5 footprints beyond the image's edge, never a ground point it sees, while
// points just outside the box (outside_validity_box, a 10% margin) are extrapolated and only counted.
constexpr double kFarOutsideScales = 10;

struct RpcModel {
  double err_bias = 0, err_rand = 0;  // metres (RPC00B ERR_BIAS, ERR_RAND); carried, not used
  double line_off = 0, samp_off = 0, lat_off = 0, lon_off = 0, height_off = 0;
  double line_scale = 1, samp_scale = 1, lat_scale = 1, lon_scale = 1, height_scale = 1;
  RpcPoly line_num{}, line_den{}, samp_num{}, samp_den{};
  // Direct model (image -> ground), present in DIMAP files: lon = lon_num / lon_den * lon_scale + lon_off,
  // lat likewise, of normalized (sample, line, height). Used only as the first guess of localize().
  bool has_direct = false;
  RpcPoly lon_num{}, lon_den{}, lat_num{}, lat_den{};

  // Ground (lon, lat degrees, h metres) -> pixel (x, y).
  Eigen::Vector2d project(double lon, double lat, double h) const;
  Eigen::Vector2d project(const Eigen::Vector3d& llh) const { return project(llh[0], llh[1], llh[2]); }
  // The same with its 2x3 Jacobian d(x, y) / d(lon, lat, h).
  Eigen::Vector2d project(const Eigen::Vector3d& llh, Eigen::Matrix<double, 2, 3>& J) const;
  // Templated projection (T = double or a Ceres jet): xy = project(llh).
  template <typename T>
  void project_t(const T* llh, T* xy) const {
    T L = (llh[0] - lon_off) / lon_scale, P = (llh[1] - lat_off) / lat_scale, H = (llh[2] - height_off) / height_scale;
    T t[20];
    rpc_terms(L, P, H, t);
    xy[0] = rpc_eval(samp_num, t) / rpc_eval(samp_den, t) * samp_scale + samp_off;
    xy[1] = rpc_eval(line_num, t) / rpc_eval(line_den, t) * line_scale + line_off;
  }
  // Inverse at height h: the (lon, lat) in degrees whose projection is pixel (x, y), by Gauss-Newton on
  // project() from the direct model (when present) or the model's centre; |residual| < 1e-8 px.
  // Throws NumericalError when it does not converge.
  Eigen::Vector2d localize(double x, double y, double h) const;
  // The direct model's (lon, lat) of pixel (x, y) at height h (has_direct only).
  Eigen::Vector2d direct(double x, double y, double h) const;

  // True when the ground point lies outside the model's validity box, widened by `margin` (normalized
  // |lon|, |lat|, |h| above margin; 1.1: a tenth beyond lon_off +- lon_scale, ...).
  bool outside_validity_box(const Eigen::Vector3d& llh, double margin = 1.1) const;

  // Why the ground point is one the model says nothing about ("" when it is not): a latitude outside
  // [-90, 90], a longitude outside [-180, 360), or a normalized lon, lat or h beyond kFarOutsideScales
  // (the point farther than that many of the model's scales from its offsets). The polynomials are fitted
  // within +-1; beyond a few scales their cubic terms (up to 1000 times as large at 10) give a pixel that
  // means nothing (the antipode, the Earth's centre), where a pole's nan would at least say so.
  std::string outside_domain(const Eigen::Vector3d& llh) const;

  // Height range the model is valid for: height_off -/+ height_scale.
  double height_min() const { return height_off - height_scale; }
  double height_max() const { return height_off + height_scale; }

  bool operator==(const RpcModel& o) const;
  bool operator!=(const RpcModel& o) const { return !(*this == o); }
};

// The pixel of image `b` that sees the ground point of pixel (x, y) of image `a` at height h (metres);
// nullopt where the localization in `a` fails.
std::optional<Eigen::Vector2d> epipolar_point(const RpcModel& a, const RpcModel& b, double x, double y, double h);
// Epipolar curve: the pixels of image `b` that see the ground points of pixel (x, y) of image `a` at
// `samples` heights evenly spread over [h_lo, h_hi] (metres; samples >= 2). Row k: (x_b, y_b, h).
// Heights where localization fails are skipped.
std::vector<Eigen::Vector3d> epipolar_curve(const RpcModel& a, const RpcModel& b, double x, double y, double h_lo,
                                            double h_hi, int samples = 16);
// Distance (pixels) from pixel q of image b to the epipolar curve of pixel p of image a over [h_lo, h_hi]
// (the curve as a polyline of `samples` vertices).
double epipolar_distance(const RpcModel& a, const RpcModel& b, const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                         double h_lo, double h_hi, int samples = 16);

// Terrain-independent fit of an RPC00B to a ground -> image function over the volume
// [lon0, lon1] x [lat0, lat1] x [h0, h1] (a grid of n x n x nh points, plus a check grid between them):
// offsets at the centres, scales the half ranges (image: of the projected grid), numerators and
// denominators (constant term of each denominator 1) by iteratively reweighted linear least squares
// with a small ridge. The result's fit error is measured on the check grid.
struct RpcFitVolume {
  double lon0 = 0, lon1 = 0, lat0 = 0, lat1 = 0, h0 = 0, h1 = 0;
  int n = 21, nh = 9;
};
struct RpcFit {
  RpcModel model;
  double rms_px = 0, max_px = 0;  // on the check grid
};
RpcFit fit_rpc(const std::function<Eigen::Vector2d(const Eigen::Vector3d& llh)>& ground_to_image,
               const RpcFitVolume& volume);

// The same model under other offsets and scales (`to`'s; its polynomials are not used), exactly: an affine
// change of each normalized ground variable maps a cubic to a cubic (binomial expansion of each term),
// and new image offsets and scales only mix each denominator into its numerator. Both rational functions
// are then divided by their denominator's constant term, so that it is 1 again (it must not be 0 at the
// new centre). The direct model is dropped. Used where a form stores offsets and scales at a fixed
// precision (the NITF RPC00B TRE: whole pixels and metres, 1e-4 degree).
RpcModel renormalized_rpc(const RpcModel& m, const RpcModel& to);

// The volume an RPC's normalization describes (offsets -/+ scales), for refitting a modified model.
RpcFitVolume rpc_volume(const RpcModel& m);

}  // namespace tpkit
