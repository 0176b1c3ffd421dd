// Bundle adjustment of RPC cameras from tie points (rpc-adjust): one image-space bias per image
// (rpc_bias.hpp: shift, drift or affine) and one ground point (lon, lat, h) per track are the unknowns;
// each observation gives the residual  bias_v(rpc_v(g_t)) - x_tv  (pixels), under a robust (Huber) loss;
// weak Gaussian priors pull each bias term to 0 (sigma: prior_shift_px for the shifts, prior_linear for the
// linear terms, per pixel); `fixed` images keep a zero bias; a height prior (constant H +- S or a DEM) adds
// (h_t - H(lon_t, lat_t)) / S per track. Solved with Ceres (Levenberg-Marquardt, Schur elimination of the
// points).
//
// Gauge: without ground control, tie points fix only the relative geometry: a common shift of every image
// is a ground translation (and a common affine term a ground deformation) that the tie points cannot see.
// With at least one --fixed image the others are adjusted to it; with none, the priors choose the
// smallest-bias solution. Heights depend on that choice; a height prior fixes their level.
#pragma once
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "tpkit/rpc/rpc_bias.hpp"
#include "tpkit/rpc/rpc_ground.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

struct AdjustImage {
  std::string path;
  long width = 0, height = 0;
  RpcModel model;
  bool fixed = false;
};

// One track: views (image index, observed pixel) of one ground point; where it came from for messages.
struct AdjustTrack {
  std::string source;
  long line = 0;  // in source (0: unknown)
  long long id = 0;
  std::vector<std::pair<int, Eigen::Vector2d>> views;
};

struct HeightPrior {
  // Height (m above the ellipsoid) at (lon, lat) and, when grad is not null, its derivatives (m per degree of
  // lon, lat); false where unknown (off the DEM). Empty: no prior.
  std::function<bool(double lon, double lat, double& h, double* grad)> at;
  double sigma = 0;  // m
};

struct AdjustOptions {
  BiasModel model = BiasModel::affine;
  double prior_shift_px = 100;  // sigma of the shift terms' prior, pixels
  double prior_linear = 0.01;   // sigma of the linear terms' prior, pixels per pixel
  double loss_px = 1;           // Huber loss scale, pixels
  double flag_px = 1;           // tracks whose RMS after the fit exceeds this are flagged
  HeightPrior height;
  int threads = 1;
  int max_iterations = 100;
  bool progress = false;        // progress line on a terminal (tool_support Progress)
};

struct AdjustResult {
  std::vector<ImageBias> bias;                // per image
  std::vector<Eigen::Vector3d> ground;        // per track: lon, lat, h
  std::vector<double> sigma_h;                // per track, m: sigma0 * height_sigma_unit
  std::vector<double> rms_before, rms_after;  // per track, px (initial: zero bias, least-squares point)
  std::vector<char> flagged;                  // per track: rms_after > flag_px
  std::vector<char> initial_ok;               // per track: the zero-bias intersection converged
  // Per observation, in track order then view order: residual (projected minus observed) before and after.
  std::vector<int> obs_track, obs_image;
  std::vector<Eigen::Vector2d> obs_xy, res_before, res_after;
  double sigma0 = 0;  // per-coordinate RMS after (pixels)
  int iterations = 0;
  std::string solver_report;
};

// InputError (the track's file and line) for a track with fewer than two views, a view of an image out of
// range, two views of one image, or a view off its image (images with a size); NumericalError for none.
void check_tracks(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks);

// Throws what check_tracks throws; NumericalError when no track can be intersected, when the cost is not
// finite (an observation or a prior out of range), when the DEM or height prior reaches none of the
// points, or when most tracks stay above flag_px after the fit (the models, the tracks or --flag are
// wrong: the figures are in the message).
AdjustResult adjust_rpcs(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                         const AdjustOptions& options);

// Does a height prior (options.height: --height-prior or --dem) contradict the tie points? The adjustment
// is solved again without it and the two compared: the prior contradicts them when, with it, the RMS
// after the fit exceeds the free fit's by more than 20% and 0.02 px, or when the median of
// |prior - free height| over the tracks the prior covers exceeds 3 prior sigmas. The free fit is as
// well posed as the problem is without a prior (--fixed images; else the bias priors hold the datum).
struct HeightPriorCheck {
  bool contradicts = false;
  double rms_with = 0, rms_without = 0;  // px, after the fit
  long flagged_with = 0, flagged_without = 0;
  long covered = 0;                      // tracks whose free ground point the prior gives a height for
  double median_dh = 0, median_abs_dh = 0;  // prior minus free height, m
  double sigma = 0;                      // the prior's sigma, m
  std::string figures;                   // one line: the figures above
};
HeightPriorCheck check_height_prior(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                                    const AdjustOptions& options, const AdjustResult& with_prior);

// RMS summary of residuals: sqrt(mean |r|^2) over the observations selected (all when `image` < 0).
double residual_rms(const AdjustResult& r, bool after, int image = -1);

// Reprojection residuals of tracks not used in the fit (held-out): each intersected with the given
// biases; returns sqrt(mean |r|^2) over their observations, and their count in *n.
double held_out_rms(const std::vector<AdjustImage>& images, const std::vector<ImageBias>& bias,
                    const std::vector<AdjustTrack>& tracks, long* n = nullptr);

// Ground points of tracks on the delivered models (tp-ground): each track intersected on its own
// (rpc_ground.hpp intersect_rpc), flagged, and the run refused when the models do not fit the tracks.
enum GroundFlag : int {
  kGroundResidual = 1,     // RMS residual above flag_px
  kGroundOutsideBox = 2,   // outside a view's validity box (normalized ground coordinate beyond +-1.1)
};
struct GroundOptions {
  double flag_px = 2;
  int threads = 1;
};
struct GroundSolution {
  std::vector<RpcIntersection> points;  // per track (ok false: not intersected)
  std::vector<int> flags;               // per track, GroundFlag bits
  long intersected = 0, residual_flagged = 0, outside_box = 0;
  double rms_px = 0, sigma0 = 0;        // over the intersected tracks' observations: RMS of |r|, and per coordinate
};
// NumericalError when no track can be intersected, or when most tracks have an RMS above flag_px (the
// message gives the count and median: a wrong model, swapped offsets, another image's model).
GroundSolution ground_points(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                             const GroundOptions& options);

// Tracks of several files on one set of images: each file's image k is matched to one of `images` (same
// path as written, the same file, relative to the tracks file's folder or not, or else the one image of that
// file name); InputError (file: imageK 'PATH' is not one of the images) otherwise. Track ids are the files'.
std::vector<AdjustTrack> gather_tracks(const std::vector<std::string>& files, const std::vector<std::string>& images);

// The smallest sigma of a height prior (m): a millimetre; below it the weights overflow the cost.
constexpr double kMinHeightSigma = 1e-3;

// Height prior from "H+-S" / "H±S" / "H,S" (metres, S >= kMinHeightSigma); UsageError naming --height-prior otherwise.
HeightPrior parse_height_prior(const std::string&);

// Height prior from a DEM (image_io.hpp GeoGrid, heights above the ellipsoid), bilinear between its
// samples; no prior off the grid or next to no-data samples. sigma in metres.
struct GeoGrid;
HeightPrior dem_height_prior(const GeoGrid& dem, double sigma);

// The ground the images' models are valid on: the union of their boxes (lon_off +- lon_scale, lat_off +-
// lat_scale), degrees; what a DEM must cover.
struct GeoBounds;
GeoBounds models_bounds(const std::vector<AdjustImage>& images);
GeoBounds model_bounds(const RpcModel& m);  // one model's box

// Figure: per image, the residual vectors at the observed points before (zero bias) and after the
// adjustment, exaggerated by one common factor (scale bar), over the image extent.
void plot_rpc_residuals(const std::string& path, const std::vector<AdjustImage>& images, const AdjustResult& r,
                        const std::string& title);

// The adjusted RPC00B of an image: its model with the bias folded in, refitted (fit_rpc) over the image's
// footprint (the image corners localized at heights h_lo .. h_hi, m).
RpcFit fold_bias(const RpcModel& model, const ImageBias& bias, long width, long height, double h_lo, double h_hi);

}  // namespace tpkit
