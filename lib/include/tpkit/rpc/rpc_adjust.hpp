// Bundle adjustment of RPC cameras from tie points (rpc-adjust): one image-space bias per image
// (rpc_bias.hpp: shift, drift or affine) and one ground point (lon, lat, h) per track are the unknowns;
// each observation (view k of track t, in image v) gives the weighted residual
//     (bias_v(rpc_v(g_t)) - x_tk) * s_ref / sigma_tk          (pixels)
// under a robust (Huber) loss; weak Gaussian priors pull each bias term to 0 (sigma: prior_shift_px for
// the shifts, prior_linear for the linear terms, per pixel); `fixed` images keep a zero bias; a height
// prior (constant H +- S or a DEM) adds (h_t - H(lon_t, lat_t)) / S per track. Solved with Ceres
// (Levenberg-Marquardt, Schur elimination of the points).
//
// Weights. sigma_tk (pixels) is the standard deviation of the observed position: AdjustTrack::sigma
// (tracks: column sigmaK of view K; matches: the record's sigma, which is that of (x2, y2) relative to
// (x1, y1), split as sigma / sqrt(2) on each of the two views). Observations without one (no column, or
// nan) take default_sigma_px (by default the median of the sigmas given, 1 px when none is given). Every
// sigma is floored at kMinObservationSigma (0.02 px) so that no observation dominates; use_sigma = false
// weighs every observation at default_sigma_px (1 px when NaN). The sigmas weigh observations against
// each other: s_ref, the median sigma over the observations, keeps their common scale at the unweighted
// fit's (an observation of sigma s_ref weighs as one of 1 px did without sigmas), so that the bias priors
// and the height prior keep their balance with the tie points. (Absolute weights 1 / sigma made the tie
// points 2500 times heavier at LSM sigmas of 0.02 px, the priors that hold the unobservable height plane
// (see Gauge) 2500 times weaker, and the fit drift along it: on Marseille a 57 px shift and 0.08 px/px
// linear terms at the same RMS; LSM sigmas are also about 4 times below the residuals there.) Without
// sigmas (or all equal) the fit is the unweighted one.
// The Huber scale and the flag threshold stay in pixels: an observation's loss turns linear where its
// pixel residual |bias_v(rpc_v(g_t)) - x_tk| exceeds loss_px, whatever its sigma (the Huber scale on the
// weighted residual is loss_px * s_ref / sigma_tk); a track is flagged on the RMS of its pixel residuals.
// Every residual and RMS that the result reports is in pixels, unweighted, except sigma0_weighted.
//
// Per-view blunders (AdjustOptions::drop_views): one wrong view (a mismatch in one image of a long track)
// should cost that view, not the track. After the robust fit, each track of 3 or more views whose RMS
// over all of them, re-intersected on the adjusted models, exceeds flag_px is re-intersected without each
// of its views in turn; the view whose removal leaves the smallest RMS is dropped, again while the track
// stays above flag_px and fewer views would be dropped than kept (at most (n - 1) / 2 of n views); the
// track is kept when what remains is under flag_px and no other removal fits within twice that RMS (a
// blunder along the epipolar line of the pair another removal leaves is not named: the track stays
// flagged), and the fit is solved again without the dropped views, started from the last solution. The
// drops are decided afresh on each fit's biases (one decided on a fit that still held the blunders may
// be undone), until they stay the same (three refits at most). Dropped observations stay in the result
// (obs_dropped, their residual to the refitted point);
// a track's rms_after is over its kept views. Only tracks no view removal saves stay flagged.
//
// Tracks of any length: a track has 2 or more views, each of a distinct image; a view a track is not seen
// in is simply absent (files: a "nan nan" pair, never read as a coordinate). A matches record is a track
// of its two images.
//
// Ground control (AdjustOptions::control, rpc-adjust --gcp): each control point's ground position is an
// unknown (lon, lat, h) with a Gaussian prior at its known position, residual (g - known) in metres east,
// north, up (metres per degree at the known latitude, WGS 84) times s_ref / sigma_m; each of its image
// measurements is an observation as a tie point's, weight s_ref / sigma_px, without the robust loss (a
// control point is trusted; one that contradicts the tie points is found by check_gcps). With control
// points no image needs to be fixed: they hold the common shift and the height level; the bias priors stay.
//
// Gauge: without ground control, tie points fix only the relative geometry: a common shift of every image
// is a ground translation (and a common affine term a ground deformation) that the tie points cannot see.
// With at least one --fixed image the others are adjusted to it; with none, the priors choose the
// smallest-bias solution. Heights depend on that choice; a height prior fixes their level.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "tpkit/core/formats.hpp"
#include "tpkit/ground/gcp_file.hpp"
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
  // Per view, in the order of `views`: the standard deviation of the observed position (pixels, each
  // coordinate); empty, or NaN for a view: not given (AdjustOptions::default_sigma_px).
  std::vector<double> sigma;
};

// The smallest sigma an observation is weighted with (pixels): an LSM sigma below it (or 0) is taken as
// this, so that no observation dominates the fit.
constexpr double kMinObservationSigma = 0.02;

// The Huber scale of a height prior, in its sigmas (HeightPrior::loss).
constexpr double kHeightPriorLossSigmas = 1;

// A ground control point in the adjustment (gcp_file.hpp Gcp, its images matched: gcps_to_adjust).
struct AdjustControl {
  std::string source;
  long line = 0;
  long long id = 0;
  Eigen::Vector3d llh = Eigen::Vector3d::Zero();        // known: lon, lat (deg), h (m, ellipsoid)
  Eigen::Vector3d sigma_enu = Eigen::Vector3d::Ones();  // m
  std::vector<std::pair<int, Eigen::Vector2d>> views;   // image index, measured pixel
  std::vector<double> sigma_px;                         // per view
  std::vector<long> view_line;                          // per view: its line in source
};

struct HeightPrior {
  // Height (m above the ellipsoid) at (lon, lat) and, when grad is not null, its derivatives (m per degree of
  // lon, lat); false where unknown (off the DEM). Empty: no prior.
  std::function<bool(double lon, double lat, double& h, double* grad)> at;
  double sigma = 0;  // m
  // Huber scale of the prior's residual (h - H) / sigma, in sigmas (0: none, a plain Gaussian prior). A
  // surface model disagrees with some tie points by far more than its sigma (a tree top over the ground,
  // a roof edge, a DSM flown on another date): past loss sigmas each pulls with a bounded force. (A
  // redescending loss, Cauchy's, lets a prior whose every point is far off pull nothing: a DEM 200 m
  // off then moved no point and passed for agreeing.)
  double loss = kHeightPriorLossSigmas;
  // The tie points' a posteriori sigma0 in their weighted units (AdjustResult::sigma0_weighted of the fit
  // without the prior; 1: as nominal). The prior's residual is (h - H) / sigma * tie_sigma0 (floored at
  // kMinTieSigma0), so that it weighs against the tie points' actual precision, not the nominal one an
  // observation of sigma s_ref is given (1 px): noise-free tie points (sigma0 0.001) are not bent to a
  // DEM's noise, while the level and plane they cannot see are still the prior's.
  double tie_sigma0 = 1;
};
constexpr double kMinTieSigma0 = 0.1;

struct AdjustOptions {
  BiasModel model = BiasModel::affine;
  double prior_shift_px = 100;  // sigma of the shift terms' prior, pixels
  double prior_linear = 0.01;   // sigma of the linear terms' prior, pixels per pixel
  double loss_px = 1;           // Huber loss scale, pixels
  double flag_px = 1;           // tracks whose RMS after the fit exceeds this are flagged
  bool use_sigma = true;        // weigh observations by their sigma (false: every one at default_sigma_px)
  double default_sigma_px = NAN;  // sigma of observations without one; NaN: median of those given, else 1 px
  HeightPrior height;
  std::vector<AdjustControl> control;  // ground control points (see the header comment)
  int threads = 1;
  int max_iterations = 100;
  bool progress = false;        // progress line on a terminal (tool_support Progress)
  // Return a fit that fit_trust() refuses instead of throwing its error, so that the caller can first ask
  // whether a height prior or the GCPs dragged it there (check_height_prior, check_gcps name them).
  bool keep_untrusted = false;
  // Drop the blunder views of flagged tracks and refit (see the header comment).
  bool drop_views = true;
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
  std::vector<double> obs_sigma;  // per observation: the sigma it was weighted with (px, floored or default)
  std::vector<char> obs_dropped;  // per observation: 1 a blunder view dropped from the fit (AdjustOptions::drop_views)
  std::vector<int> views_dropped;  // per track: its views dropped
  long dropped_views = 0;         // observations dropped, over all tracks
  long tracks_with_dropped = 0;   // tracks that lost a view (kept unless still above flag_px)
  int drop_rounds = 0;            // fits solved again after dropping views
  long obs_with_sigma = 0;        // observations whose sigma was given (and used)
  double default_sigma_px = 1;    // the sigma of those without one
  double reference_sigma_px = 1;  // s_ref: the median sigma over the observations (weight 1)
  double sigma0 = 0;              // per-coordinate RMS after (pixels)
  double sigma0_weighted = 0;     // per-coordinate RMS of the weighted residuals after (px at s_ref)
  std::vector<Eigen::Vector3d> control_ground;  // per control point: its adjusted position (lon, lat, h)
  int iterations = 0;
  bool converged = true;          // false: the solver stopped at max_iterations (or another limit) first
  std::string solver_report;
};

// InputError (the track's file and line) for a track with fewer than two views, a view of an image out of
// range, two views of one image, a view off its image (images with a size), a coordinate that is not
// finite, or a sigma list of another length than the views, or a sigma negative or infinite;
// NumericalError for none.
void check_tracks(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks);

// Throws what check_tracks throws; NumericalError when no track can be intersected, when the cost is not
// finite (an observation or a prior out of range), when the DEM or height prior reaches none of the
// points, or (unless keep_untrusted) with fit_trust's message for a fit it cannot stand behind.
AdjustResult adjust_rpcs(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                         const AdjustOptions& options);

// Can the fit be trusted? Not when half or more of the intersected tracks keep an RMS above flag_px after
// it (the models, the tracks or --flag are wrong), nor when half or more of the tracks that view one image
// do (that image's model is wrong where the others hold: another image's, or one that diverges over the
// image, as a corrupted cubic term does, which no bias model follows). Half, not most: the robust fit
// holds the tracks it fits and flags the rest, so a fit that fits only half of them fits no model (a
// diverging model flagged exactly half of the tracks, and its models were written). Empty `figures`:
// trusted.
struct FitTrust {
  std::string figures;  // "N of M tracks keep an RMS above F px after the fit (...)", or that of one image
  std::string cause;    // what is wrong, in words
  bool ok() const { return figures.empty(); }
  std::string message() const { return figures + ": " + cause; }
};
FitTrust fit_trust(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks, const AdjustResult& r,
                   double flag_px);

// The spread of a height prior about the tie points: dh = prior height minus the height of the free fit
// (no prior), over the free fit's tracks that it keeps (not flagged) and the prior covers. Its median is
// the prior's level against the tie points' (which the delivered models set, see Gauge), its NMAD (1.4826
// median |dh - median|) how far the prior and the tie points disagree point by point: the prior's own
// error (a first-return DSM's trees, SRTM's 90 m posting on steep slopes, a survey of another date) and the
// points' height noise together.
struct HeightPriorSpread {
  long covered = 0;
  double median_dh = NAN, nmad_dh = NAN;  // m
  double median_sigma_h = NAN;            // m: the free points' own height precision (AdjustResult::sigma_h)
};
HeightPriorSpread height_prior_spread(const HeightPrior& prior, const AdjustResult& free_fit);

// A prior's sigma estimated from the data where none is given (rpc-adjust --dem without --dem-sigma): the
// NMAD of dh, floored at kPriorPrecisionRatio times the free points' median height precision and at
// kMinEstimatedHeightSigma. The floor keeps the prior from overruling the tie points where they see the
// heights well (a point is pulled by sigma_h^2 / (sigma_h^2 + sigma^2) of its difference, 10% at 3
// times): what the tie points cannot see, the level and plane of the block, the prior still holds, from
// every point (on the Jacksonville block a first-return lidar at its NMAD, 0.71 m against points of 0.58
// m, bent the tie points from 0.26 to 0.33 px RMS and flagged 331 tracks more).
constexpr double kMinEstimatedHeightSigma = 0.1;  // m
constexpr double kPriorPrecisionRatio = 3;
double estimated_height_sigma(const HeightPriorSpread& spread);

// The largest bias (pixels, at its centre) an image's delivered model can have: kGroundMaxBiasPx, or
// kGroundStatedErrors times its stated error (RPC00B ERR_BIAS and ERR_RAND, root sum of squares, in its
// pixels: model_gsd) where that is more.
double delivered_bias_bound_px(const AdjustImage& image);
// Beyond this change of a model's bias (px) a prior that does not contradict is still said: more than most
// delivered models are off (kGcpWarnPx's reasoning), and what a DEM over another vertical datum forces.
constexpr double kPriorWarnBiasPx = 30;

// Does a height prior (options.height: --height-prior or --dem) contradict the tie points? The adjustment
// is solved again without it (or `free_fit` is that fit) and the two compared: the prior contradicts them
// when, with it, the RMS after the fit (over the tracks neither fit flags nor lost a view in: a few
// blunders held to the prior's heights are no contradiction) exceeds the free fit's by more than 20% and a
// quarter of the reference sigma s_ref, when it flags more than max(10, 1% of the tracks) tracks more, or
// when its level is off: |median dh| (HeightPriorSpread) beyond 3 NMAD of dh (floored as
// estimated_height_sigma) while the biases it forces (the change of an image's bias at its centre from
// the free fit's) exceed what a delivered model can be off (delivered_bias_bound_px). The free fit's
// level is the delivered models' (Gauge): a prior is there to correct it, by as much as their errors allow
// (a Pleiades model 60 px off: 89 m on the Mont Ventoux pair). Tie points cannot tell a model that far off
// from a DEM over the wrong datum; only the models' stated accuracy can.
struct HeightPriorCheck {
  bool contradicts = false;
  double rms_with = 0, rms_without = 0;  // px, after the fit, over the tracks neither fit flags
  long common_tracks = 0;                // those tracks
  long flagged_with = 0, flagged_without = 0;  // contradiction too when the prior flags more than max(10, 1%) more
  long covered = 0;                      // tracks whose free ground point the prior gives a height for
  double median_dh = 0, median_abs_dh = 0;  // prior minus free height, m
  double nmad_dh = 0;                    // its NMAD, m
  double level_limit = 0;                // 3 NMAD of dh (floored), m
  double forced_bias_px = 0;             // the largest change of an image's bias the prior forces (px at its centre)
  int forced_image = -1;                 // that image (0-based)
  double bias_bound_px = 0;              // its delivered_bias_bound_px
  bool impossible = false;               // the level contradiction: biases no delivered model has (refused)
  double sigma = 0;                      // the prior's sigma, m
  std::string figures;                   // one line: the figures above
};
HeightPriorCheck check_height_prior(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                                    const AdjustOptions& options, const AdjustResult& with_prior,
                                    const AdjustResult* free_fit = nullptr);

// The points of GCP files as the adjustment's: those of `role`, each measurement's image matched to one of
// `images` as a tracks file's are (gather_tracks). InputError (file:line) for an image that is none of
// them (or ambiguous), a measurement off its image (images with a size; 0.5 px of slack beyond the
// edge pixels' edges), a control point measured in no image, a check point measured in fewer than two
// (it could not be intersected).
std::vector<AdjustControl> gcps_to_adjust(const std::vector<Gcp>& gcps, GcpRole role, const std::vector<AdjustImage>& images);

// A point measured in the images intersected on the models (biases applied when `bias` is not null):
// RpcIntersection per point (ok false: fewer than two views or no convergence), and per view the
// projection of its KNOWN position minus the measurement (pixels).
struct ControlEvaluation {
  std::vector<RpcIntersection> intersection;
  std::vector<std::vector<Eigen::Vector2d>> known_residual_px;
};
ControlEvaluation evaluate_controls(const std::vector<AdjustImage>& images, const std::vector<ImageBias>* bias,
                                    const std::vector<AdjustControl>& points);

// Do the control points contradict the tie points? The adjustment is solved again without them (the
// gauge then held by --fixed images or the bias priors) and compared: they contradict when, with them,
// the tie points' RMS after the fit (over the tracks neither fit flags) exceeds the free fit's by more
// than 20% and a quarter of their reference sigma s_ref (noisy GCPs bend noise-free tie points a little:
// 0.04 px at 1 px sigma on a tp-synth block; only a fit that the tie points' own sigma cannot explain
// counts), or when a control point's normalized residual after the fit (the largest of its
// ground residuals over their sigmas and its image residuals over their sigmas) exceeds 5: a GCP that the
// other GCPs and the tie points cannot fit (a blunder in its coordinates or its measurements), or when
// they flag more than max(10, 1% of the tracks) tracks more (as check_height_prior: GCPs that drag the
// fit over --flag).
struct GcpCheck {
  bool contradicts = false;
  double rms_with = 0, rms_without = 0;  // px, over the tracks neither fit flags
  long common_tracks = 0;
  long flagged_with = 0, flagged_without = 0;
  long long worst_id = 0;                // the control point of the largest normalized residual
  double worst_normalized = 0;           // that residual (sigmas)
  Eigen::Vector3d worst_enu = Eigen::Vector3d::Zero();  // its ground residual (adjusted minus known, m)
  std::string figures;                   // one line: the figures above
};
GcpCheck check_gcps(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                    const AdjustOptions& options, const AdjustResult& with_gcps);

// The GCPs against the delivered models, before any adjustment. GCPs wrong together (all moved by a wrong
// zone, datum or coordinate order; heights above the geoid read as ellipsoidal) pull the whole block with
// them, and the tie points, which see no absolute position, agree with them afterwards: only the
// delivered models can tell. Per point (control and check): the RMS over its measurements of the
// projection of its known position minus the measurement (pixels); their median is the decision figure
// (a blunder or two moves no median). Also, over the measurements, the median offset (projected minus
// measured, pixels) and the median ground offset (known minus the measurement localized at the known
// height, metres east, north), and over the points measured in two or more images, the median of the
// known height minus the height intersected on the delivered models (m).
struct GcpModelCheck {
  long points = 0, measurements = 0, intersected = 0;
  std::vector<double> residual_px;                     // per point, in the order given
  double median_px = 0;                                // median of residual_px
  long long worst_id = 0;                              // the point of the largest residual_px
  double worst_px = 0;
  Eigen::Vector2d offset_px = Eigen::Vector2d::Zero();  // median projected minus measured, x y
  Eigen::Vector2d offset_en = Eigen::Vector2d::Zero();  // median known minus localized, m east, north
  double offset_u = std::nan("");                      // median known minus intersected height, m
  double spread_u = std::nan("");                      // median |dh - offset_u|, m
  double geoid_n = std::nan("");                       // EGM96 undulation at the points (NaN: no grid)
  bool geoid_like = false;                             // |offset_u| is that undulation (see check_gcps_on_models)
  std::string problem;                                 // what is wrong, in words ("": nothing: median_px and heights fine)
  bool refuse = false;                                 // median_px above kGcpRefusePx
  std::string figures;                                 // one line: the figures above
};
// Thresholds on median_px. Delivered models are within a few pixels to a few tens of pixels of the
// ground: Pleiades 8.5 m CE90 without GCPs (17 px at 0.5 m), WorldView-3 3.5 m CE90 (11 px at 0.31 m);
// the Jacksonville WorldView-3 models disagree with each other by a few pixels, tp-synth blocks' biases
// are below 10 px. Above 30 px a GCP set is suspect (warned; an error under --strict); above 150 px (75 m
// at 0.5 m GSD, nine times Pleiades' specified CE90) no delivered model explains it: refused unless forced.
constexpr double kGcpWarnPx = 30, kGcpRefusePx = 150;
// geoid_like: |offset_u| within max(5 m, 20% of N) of |N| (N the EGM96 undulation, |N| >= 15 m so that
// it is told from the delivered models' own height error of a few metres) and the points agree on it
// (spread_u below the same tolerance): heights above the geoid given as ellipsoidal, or the reverse.
GcpModelCheck check_gcps_on_models(const std::vector<AdjustImage>& images, const std::vector<AdjustControl>& points);

// RMS summary of residuals: sqrt(mean |r|^2) over the observations selected (all when `image` < 0), pixels.
double residual_rms(const AdjustResult& r, bool after, int image = -1);
// The same after the fit, over the observations of the tracks not flagged (AdjustResult::flagged), less
// the views dropped (AdjustResult::obs_dropped).
double inlier_rms(const AdjustResult& r, int image = -1);

// Per image, over the tracks that were intersected (AdjustResult::initial_ok): its observations, the
// tracks that view it by their number of views (length -> count), the RMS of its residuals before and
// after (pixels, as residual_rms), and the median sigma of its observations (px).
struct ImageReport {
  long observations = 0;
  std::map<int, long> tracks_by_length;
  double rms_before = 0, rms_after = 0;
  double rms_after_unflagged = 0;  // over the observations of the tracks not flagged
  double median_sigma = 0;
};
std::vector<ImageReport> image_reports(size_t images, const std::vector<AdjustTrack>& tracks, const AdjustResult& r);
// Tracks by their number of views, over the intersected tracks: length -> count.
std::map<int, long> tracks_by_length(const std::vector<AdjustTrack>& tracks, const AdjustResult& r);
// "2:5120 3:4155"
std::string format_lengths(const std::map<int, long>& by_length);

// Reprojection residuals of tracks not used in the fit (held-out): each intersected with the given
// biases; returns sqrt(mean |r|^2) over their observations, and their count in *n.
double held_out_rms(const std::vector<AdjustImage>& images, const std::vector<ImageBias>& bias,
                    const std::vector<AdjustTrack>& tracks, long* n = nullptr);

// Ground points of tracks on the delivered models (tp-ground): each track intersected on its own
// (rpc_ground.hpp intersect_rpc), flagged, and the run refused when the models cannot be right.
enum GroundFlag : int {
  kGroundResidual = 1,     // RMS residual above flag_px
  kGroundOutsideBox = 2,   // outside a view's validity box (normalized ground coordinate beyond +-1.1)
};
struct GroundOptions {
  double flag_px = 2;
  int threads = 1;
};
// Delivered models disagree by a bias of a few pixels to a few tens (Pleiades 8.5 m CE90, WorldView-3
// 3.5 m CE90): their points are a normal first look, written with the tracks flagged and a warning. A
// bias larger than kGroundMaxBiasPx (75 m at 0.5 m, nine times Pleiades' CE90; kGcpRefusePx's reasoning),
// or than kGroundStatedErrors times a model's stated error (RPC00B ERR_BIAS and ERR_RAND, root sum of
// squares, in its pixels) where that is more, is no delivered model's.
constexpr double kGroundMaxBiasPx = 150, kGroundStatedErrors = 10;
struct GroundSolution {
  std::vector<RpcIntersection> points;  // per track (ok false: not intersected)
  std::vector<int> flags;               // per track, GroundFlag bits
  long intersected = 0, residual_flagged = 0, outside_box = 0;
  double rms_px = 0, sigma0 = 0;        // over the intersected tracks' observations: RMS of |r|, and per coordinate
  double median_rms_px = 0;             // median of the tracks' RMS
  // When most tracks are flagged: the models' disagreement told from a wrong model by fitting a shift per
  // image (rpc-adjust --model shift, the first image fixed, no prior): the RMS over the tracks after it, and
  // the largest shift it found (pixels, at its image's centre) and that image (0-based).
  bool biased = false;
  double bias_fit_rms_px = NAN, max_shift_px = NAN;
  int max_shift_image = -1;
  std::string warning;                  // "" or the figures of biased models, for the tool's warning
};
// NumericalError when no track can be intersected, or when most tracks have an RMS above flag_px and the
// models cannot be right: no shift per image fits the tracks (fit_trust: another image's model, a
// diverging one), or the bias that does is beyond kGroundMaxBiasPx or kGroundStatedErrors times a model's
// stated error (offsets swapped, another scene's model). The message gives the count, the median and the
// bias fit's figures. Biased models that fit otherwise: the points, flagged, and `warning`.
GroundSolution ground_points(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                             const GroundOptions& options);
// An image's ground sample distance at its centre and its model's height offset (m per pixel; NaN where
// the model cannot localize it).
double model_gsd(const RpcModel& m, long width, long height);

// Tracks of several files on one set of images. Each file is a tracks file or a matches file, told apart by
// its header's kind ("# tpkit matches": matches; "# tpkit tracks" or no header: tracks). Each file's image k
// is matched to one of `images` (same path as written, the same file, relative to the file's folder or not,
// or else the one image of that file name); InputError (file: imageK 'PATH' is not one of the images)
// otherwise. Track ids are the tracks files'; a matches record's is its record number (1, 2, ...).
std::vector<AdjustTrack> gather_tracks(const std::vector<std::string>& files, const std::vector<std::string>& images);

// The tracks of one tracks file; its view k is image image_of_view[k]. A view whose x and y are both NaN
// is not an observation (left out); a track keeps its observed views in file order, with column sigmaK
// (if present) as the sigma of view K. InputError (file:line) for NaN in only one of x, y, a track with
// fewer than two observed views, and a sigma that is negative or infinite.
std::vector<AdjustTrack> tracks_to_adjust(const Tracks& t, const std::vector<int>& image_of_view);
// The records of one matches file as 2-view tracks of images image1, image2; column sigma (if present; the
// sigma of (x2, y2) relative to (x1, y1)) gives each view sigma / sqrt(2). InputError (file:line) for a
// coordinate that is not finite and a sigma that is negative or infinite.
std::vector<AdjustTrack> matches_to_adjust(const Matches& m, int image1, int image2);

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

// The adjusted RPC00B of an image: its model with the bias folded in, refitted (fit_rpc) over the image's
// footprint (the image corners localized at heights h_lo .. h_hi, m).
RpcFit fold_bias(const RpcModel& model, const ImageBias& bias, long width, long height, double h_lo, double h_hi);

}  // namespace tpkit
