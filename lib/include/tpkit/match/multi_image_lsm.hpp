// Multi-image least-squares matching with geometric constraints (MPGC; Gruen & Baltsavias 1988): every
// view of a track refined together against one template, the windows tied to one ground surface through
// the images' RPC models.
//
// Conventions. Pixels: x = column, y = row, (0, 0) the centre of the top-left pixel. Ground: lon, lat
// degrees WGS84, h metres above the ellipsoid. A view's corrected projection is q = b(p), p = rpc.project(g),
// b the image's bias (rpc_bias.hpp; estimated from the tracks themselves: estimate_track_biases).
//
// Model of one track. The template is the window of the template view t (chosen per track:
// choose_template) on its own pixel grid: the pixels c of the (window x window) block centred on the pixel
// nearest p_t, within support x taper of it, offsets d = c - p_t = (u, v); p_t stays fixed. The
// terrain under the template window is a height surface over d:
//   h(d) = h0 + dh + gu u + gv v [+ cuu u^2 / 2 + cuv u v + cvv v^2 / 2]
// and the pixel of view k that sees the ground point of template pixel p_t + d at height h is, to first
// order in d and h - h0 (a satellite's map at a fixed height is affine over a window to far below 0.001 px;
// the relinearisation at the solution's h0 takes the rest),
//   q_k(d) = q_k0 + M_k d + e_k (h(d) - h0) + s_k
// where q_k0 = b_k(rpc_k(G)), G = the template ray's ground point at h0 (the bias of t removed), M_k its
// derivative along the template's pixels, e_k = dq/dh (pixels per metre: the epipolar direction), and
// s_k a free shift per view with the prior s_k ~ N(0, model_sigma^2) (what the models and biases still get
// wrong; model_sigma 0: the hard constraint, s_k = 0). Radiometry per view: T(d) ~ r0_k + r1_k I_k(q_k(d)),
// T the template's grey levels normalised to zero mean and unit deviation.
// Unknowns: the surface (dh, gu, gv[, cuu, cuv, cvv]: 3 or 6, shared by every view) and per other view
// (r0, r1, sx, sy). Compared with pairwise LSM (8 unknowns per pair, 14 quadratic), the window shapes of
// all views follow from one surface: their slopes and curvatures are measured by every view at once.
// Solved by Gauss-Newton on the dense normal equations (at most 6 + 4 (K - 1) unknowns, a few hundred
// pixels per view: forming them costs as much as one residual evaluation, and Ceres' per-pixel cost
// functions and its sparse machinery would cost several times that for tens of thousands of tracks), with
// bicubic interpolation (lsm_refine.hpp's bicubic) and the Gaussian taper exp(-|d|^2 / (2 taper^2)) as
// weights, robust by iteratively reweighted least squares (Huber, k = 2 sigma0, after two plain iterations).
// Precision: covariance sigma0^2 N^-1 (N with the prior), sigma0^2 = sum(w r^2) / (n - P); a view's
// sigma = sigma_scale x sqrt((var x + var y) / 2) of q_k(0). The template view's position is the track's definition: its
// sigma is written as the smallest of the other views' (its error relative to them is no larger).
// Acceptance per view: converged (a solve that does not converge loses the view whose position moved the
// most in its last iteration), correlation >= min_corr, moved at most max_shift from its input, sigma
// <= max_sigma; the worst failing view is dropped and the track solved again, until all pass (a track left
// with fewer than 2 views is dropped).
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

#include "tpkit/core/formats.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/match/radiometric_highpass.hpp"
#include "tpkit/match/window_size.hpp"
#include "tpkit/rpc/rpc_bias.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

struct MultiLsmOptions {
  // The window: taper 5 px (a block of 29), and where a track loses views there, taper 3 px (21; the
  // fallback below), where choose_track_size finds no bias from the larger one; else taper 3 alone.
  // Jacksonville block (tp-plan, rpc-adjust with the lidar prior, tp-ground against the lidar, slopes
  // under 5 degrees / all): taper 3 alone NMAD 0.279 / 0.482 m over 5686 / 10017 points, taper 5 alone
  // 0.253 / 0.425 m over 5491 / 9661, taper 5 with the fallback 0.261 / 0.458 m over 5767 / 10206.
  int window = 29;            // template block, pixels (odd)
  double taper = 5;           // Gaussian weight of the pixels, pixels
  double support = 3;         // only pixels within support x taper of the centre pixel
  bool curvature = true;      // the surface's second-order terms (3 more unknowns)
  // pixels: prior deviation of each view from the models (0: hard constraint); negative: each image's own
  // (MultiLsmImage::model_sigma, what the bias fit left: estimate_track_biases' residual RMS / sqrt 2), at
  // most model_sigma_max. That residual holds the pairwise matching's errors as well, so it bounds the
  // models' own from above: tp-synth's exact models leave 0.013-0.016 px and bind the views closely
  // (default scene: views 2+3 median / p90 0.022 / 0.058 px after, 0.026 / 0.076 at 0.05 px); the delivered
  // WorldView-3 models of Jacksonville leave 0.15-0.23 px, where 0.05-0.1 px gives the best ground points
  // against the lidar (NMAD on flat ground 0.326 m at 0.05, 0.337 at 0.1, 0.379 at the residual, 0.383
  // at 0.02; docs/blocks.md).
  double model_sigma = -1;
  double model_sigma_max = 0.05;
  int max_iterations = 30;
  double tolerance = 2e-3;    // pixels, on the update of every view's position
  double max_shift = 1.5;     // pixels from the view's input position
  // The sigma written and tested (max_sigma): sigma_scale times the covariance's, which counts the
  // solve's image noise as independent pixels (neighbours of a sampled, interpolated image are not) and
  // no model error. On tp-synth's default scene the RMS error of the views that move was 2.47 times the
  // covariance's RMS sigma; scaled, the ratio is 0.83-1.36 in every decile of sigma over the errors below
  // 1 px (bench_match_accuracy --synth DIR --multi --sigma-deciles).
  double sigma_scale = 2.5;
  double max_sigma = 0.375;   // pixels (0.15 of the covariance's own)
  double min_corr = 0.5;
  int relinearise = 2;        // linearisations of the geometry (the second at the first's height)
  int template_image = -1;    // refine_tracks: this image (0-based) is the template where the track has it
  // refine_tracks: also the track's views in the images it lacks where they pass on their own evidence
  bool extend = false;
  // refine_tracks, > 0: a track that loses any of its own views at window / taper is solved again at
  // fallback_window / fallback_taper, and the result with more views accepted is kept (a tie: the first).
  // The larger window is the more precise, but a change between the dates inside it (a shadow, a car)
  // fails views that the smaller one keeps.
  int fallback_window = 21;
  double fallback_taper = 3;
};

// One image of the block: its grey levels (a region; NaN = invalid), model and bias.
struct MultiLsmImage {
  const Raster* raster = nullptr;
  const RpcModel* model = nullptr;
  ImageBias bias;
  double model_sigma = NAN;  // pixels, per coordinate, for MultiLsmOptions::model_sigma < 0 (NaN: model_sigma_max)
};

enum class MultiLsmViewStatus { Ok, Template, OutOfImage, Diverged, NotConverged, Drifted, LowCorrelation, Imprecise, Geometry };
const char* to_string(MultiLsmViewStatus s);
constexpr int kMultiLsmStatusCount = 9;

struct MultiLsmView {
  int image = 0;                        // index into the images
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // input position; refined when status is Ok
  MultiLsmViewStatus status = MultiLsmViewStatus::NotConverged;
  double sigma = 0;                     // pixels
  double corr = 0;
};

struct MultiLsmResult {
  std::vector<MultiLsmView> views;  // in the input order
  int template_view = -1;           // index into views
  Eigen::Vector3d llh = Eigen::Vector3d::Zero();  // ground point of the template position (lon, lat, h)
  int iterations = 0;
  bool ok = false;                  // at least two views (the template and one more) accepted
};

// Sharpness of view k's window (mean squared gradient over the grey-level variance, 1/px^2, Gaussian
// weighted: a property of the image's blur and texture, not of its gain) times cos^2 of its view angle
// off nadir (from the model: the horizontal displacement of a ground point raised by 1 m); the view of
// the largest score is the template. Returns the index into `views`; views whose window cannot be read
// score 0.
int choose_template(const std::vector<MultiLsmImage>& images, const std::vector<MultiLsmView>& views, const MultiLsmOptions& o,
                    std::vector<double>* scores = nullptr);

// Refines one track (views: image and input position, at least 2). `template_view` < 0: choose_template.
MultiLsmResult refine_track_views(const std::vector<MultiLsmImage>& images, std::vector<MultiLsmView> views, const MultiLsmOptions& o,
                                  int template_view = -1);

// The bias of every image but `reference` (0-based; its bias is zero: the datum) from the tracks themselves:
// alternately, each track's ground point by intersection (rpc_ground.hpp) with the current biases, then
// per image the bias model fitted to the offsets observed - projected by least squares, views farther than
// 3 robust deviations (1.4826 MAD of the offsets' residual lengths) from the fit left out; `rounds` rounds.
// residual_rms: per image the RMS length of the residuals kept (the reference's: of its offsets), pixels.
std::vector<ImageBias> estimate_track_biases(const Tracks& t, const std::vector<const RpcModel*>& models, BiasModel m,
                                             int reference = 0, int rounds = 4, std::vector<double>* residual_rms = nullptr);

struct MultiLsmStats {
  long tracks = 0, tracks_written = 0, tracks_dropped = 0;
  long views = 0, views_refined = 0, views_dropped = 0;
  long views_added = 0;                       // of views_refined: in images the input track lacked (extend)
  long tracks_at_fallback = 0;                // of tracks_written: at the fallback size (fallback_window)
  long by_status[kMultiLsmStatusCount] = {};  // over the views dropped
  std::vector<long> template_count;           // per image: tracks whose template it is
};

// Every track of `t` refined (images[k] is the image of column pair k). The output: the same images,
// ids, extra columns and metadata, positions refined, views dropped set to nan, tracks left with fewer
// than 2 views left out; columns sigma1 ... sigmaK (replaced when present) and `template` (1-based image).
Tracks refine_tracks(const Tracks& t, const std::vector<MultiLsmImage>& images, const MultiLsmOptions& o, int threads,
                     MultiLsmStats* stats = nullptr);

// The local-mean high-pass (radiometric_highpass.hpp) for the refinement of a block's tracks, chosen as
// tp-match chooses it for a pair: `samples` tracks spread over the file are refined (without extension)
// on images filtered by each candidate, their views held to the models only loosely (model sigma
// kHighpassModelSigma: across its epipolar direction a view then sits where its image puts it), and the
// candidate whose accepted views scatter least across the models' epipolar directions from the template
// (the median absolute deviation of their signed distances across them from each image pair's median,
// pixels: the models' own error, mostly an offset per image pair, is common to every candidate and left
// out) wins when it scatters at least kTrackHighpassGain less than the best before it over the views both
// runs accepted (same track, template and image): over the views each run accepted, the synthetic block
// of docs/blocks.md went from 0.173 to 0.1645 px at 1 px (none chosen) and, with a few tracks more, from
// 0.1741 to 0.1651 px (1 px chosen, its ground points then 0.077 m NMAD from the true terrain instead of
// 0.034 m); over the views both accepted, 0.1406 -> 0.142 and 0.1403 -> 0.1423 px: no gain at all, the
// difference was which views each run kept. The four Jacksonville crops of that page: 0.1104 -> 0.0919 px
// at 1 px over 745 views, 0.0945 -> 0.0982 px at 2 px (1 px chosen, as before).
// images: unfiltered rasters. Spreads seen earlier, each over the views its own run accepted, unfiltered
// and at 1 px: one date (tp-synth's default scene,
// the Marseille triplet, a biased tp-synth triplet) 0.011 / 0.021, 0.058 / 0.085, 0.027 / 0.033 px;
// the Jacksonville crops of other dates, twelve 0.139 / 0.112 and four 0.118 / 0.107 px (9%: at tp-match's
// 10% those four would keep none, and their ground points would lie 0.61 m NMAD from the lidar instead
// of 0.40 m; their 0.106 px at 2 px, 1.6% below 1 px's, gave 0.45 m).
// samples: 3000 tracks. Over 1000 the paired gain moved with the sample alone: the four Jacksonville
// crops, their tracks changed a little by tp-match's larger max_shift, 17% at 1 px, then 3.6% (none
// chosen: the adjusted block's ground points 2.8 m above the lidar in median instead of 0.05 m below);
// over all their ~3500 tracks 10.5% and 8.7%.
// The sample is refined at the base size (o.fallback_window / fallback_taper when set: choose_track_size
// then chooses the window on the filtered images).
constexpr double kHighpassModelSigma = 1.0;  // pixels
constexpr double kTrackHighpassGain = 0.05;
HighpassChoice choose_track_highpass(const Tracks& t, const std::vector<MultiLsmImage>& images, const MultiLsmOptions& o, int threads,
                                     const std::vector<double>& candidates = {1.0, 2.0}, size_t samples = 3000);

// The window's size for a block (window_size.hpp's test, on tracks): a sample of the tracks (spread evenly
// over the file, as choose_track_highpass's, with its loose model sigma) refined at the fallback size
// (o.fallback_taper, o.fallback_window: the base) and at o's (the larger); over the non-template views
// refined at both against the same template, the differences of their positions along their epipolar
// direction (the height, where a window too large for curved terrain biases it) against those across
// it. The larger size is chosen (size, with the fallback) where that ratio is at most kWindowSizeMaxRatio
// and its views scatter across the epipolar directions (as choose_track_highpass measures it)
// kWindowSizeMinGain less than the base's; else the base alone. Seen (tp-synth truth, triplets' views 2+3
// median px, taper 3 -> 5): relief 15 m ratio 1.00, 0.0128 -> 0.0105 (kept); relief 150 m 2.04, 0.020 ->
// 0.031 and buildings 1.46, 0.022 -> 0.031 (refused); the Jacksonville block 1.37 (refused, though its
// ground points are nearer the lidar at taper 5 with the fallback: flat-ground NMAD 0.279 -> 0.261 m).
WindowSizeChoice choose_track_size(const Tracks& t, const std::vector<MultiLsmImage>& images, const MultiLsmOptions& o, int threads,
                                   size_t samples = 1000);
// o's window and taper set to the choice's size; the base chosen, no fallback left.
void use_track_size(const WindowSizeChoice& c, MultiLsmOptions& o);

// The "# highpass:" header value of refined tracks: the sigma used and, when chosen (given = false), the
// spreads the choice saw.
std::string describe_track_highpass(const HighpassChoice& h, bool given);

}  // namespace tpkit
