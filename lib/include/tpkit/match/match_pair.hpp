// tp-match's pipeline for one pair of images (image 1 -> image 2): SIFT by tiles (sift_tiles.hpp),
// ratio + mutual nearest neighbours searched along the epipolar band of a coarse affine F
// (guided_matching.hpp; over all descriptors, match_descriptors.hpp, if that finds no geometry), or
// along the epipolar curves of the images' RPC models when both are given (rpc_guided_matching.hpp),
// then affine fundamental matrix RANSAC
// (affine_fundamental.hpp), optional grid thinning, then least-squares matching of each verified
// match (lsm_refine.hpp) region by region. Image 1's position of every record is its keypoint
// position (the LSM template is fixed there); image 2's is refined.
//
// Records: id1 x1 y1 id2 x2 y2 kx2 ky2 [sigma corr refined] -- (kx2, ky2) is image 2's keypoint position,
// sigma the standard deviation of (x2, y2) in pixels, corr the final correlation, refined 1 when (x2, y2)
// is the LSM position and 0 when the refinement was rejected (lsm_refine.hpp's acceptance, or the refined
// position off the verified pair model): the verified match is then kept at its keypoint position with
// sigma = max(unrefined_sigma, the RANSAC inlier rms) (or dropped with keep_unrefined false), counted
// by reason either way. When one image is blurrier than the other, the sharper one's windows are blurred
// by the relative blur first (relative_blur.hpp; estimated on a sample of the matches unless given); when
// their radiometry differs within the windows (another date), both images' local mean is subtracted
// (radiometric_highpass.hpp; chosen on a sample of the matches unless given).
#pragma once
#include <array>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

#include "tpkit/core/formats.hpp"
#include "tpkit/match/guided_matching.hpp"
#include "tpkit/match/image_tiles.hpp"
#include "tpkit/match/lsm_refine.hpp"
#include "tpkit/match/radiometric_highpass.hpp"
#include "tpkit/match/relative_blur.hpp"
#include "tpkit/match/match_descriptors.hpp"
#include "tpkit/match/rpc_guided_matching.hpp"
#include "tpkit/match/sift_tiles.hpp"
#include "tpkit/match/window_size.hpp"

namespace tpkit {

// The refinement's settings for a pair (lsm_refine.hpp's defaults, and): the residual mask measures the
// correlation over the pixels that did not change between the dates (3 robust sigmas, at least half the
// window kept); the fit leaves out the pixels beyond 4 robust sigmas (tp-synth truth, triplets' views 2+3
// median / p90: building scene 0.034 / 0.154 -> 0.032 / 0.143 px, default scene 0.030 / 0.087 -> 0.029 /
// 0.082, relief 15 m 0.0156 / 0.0382 -> 0.0157 / 0.0392; Marseille's triplet ML fit 0.097 -> 0.087 px, its
// pairs' medians to the RPC epipolar curves unchanged, at 3 the pair 1-3's grew by 9%); the sigma is the
// sandwich covariance of the taper-weighted fit times 3.5, the factor that makes it predict the error on
// tp-synth truth (default scene, every decile of sigma but the last, which holds the wrong matches:
// error / sigma 0.79..1.17, with the fit's mask 0.77..1.01; La Reunion pair, distance to the RPC epipolar
// curves: 0.77..1.27); a refinement is accepted where that sigma is at most 1 px: on the Jacksonville pair 001-004
// the refinements with sigma 0.5..1 px lie 0.60 px RMS from the RPC epipolar curves, the verified
// matches whose refinement fails 0.81 px: the refined position is still the better one.
inline LsmOptions pair_lsm_options() {
  LsmOptions l;
  l.mask_k = 3;
  l.mask_fit_k = 4;
  l.min_inliers = 0.5;
  l.sigma_sandwich = true;
  l.sigma_scale = 3.5;
  l.quadratic_sigma_ratio = 0.6;
  l.sigma_floor = 0;
  l.max_sigma = 1;
  return l;
}

struct PairMatchOptions {
  SiftOptions sift;
  DescriptorMatchOptions desc;
  bool guided = true;             // descriptor search guided by a coarse epipolar geometry (guided_matching.hpp)
  GuidedMatchOptions guide;
  // RPC-guided search (rpc_guided_matching.hpp): with both models set (not owned), the search regions
  // come from the images' RPCs instead of the coarse stage; guide.ratio_margin still widens them for
  // the ratio test and the mutual check.
  const RpcModel* rpc1 = nullptr;
  const RpcModel* rpc2 = nullptr;
  RpcGuideOptions rpc_guide;
  bool rpc_only = false;          // with models: no fallback to the coarse stage when their curves hold no geometry
  double ransac_threshold = 1.0;  // pixels (geometric distance to the affine F, R^4)
  int ransac_iterations = 20000;
  uint64_t seed = 1;
  int min_inliers = 12;           // fewer verified matches: the images are taken not to overlap
  int grid = 0;                   // grid cells per side (0 = off)
  int per_cell = 4;               // matches kept per grid cell (best ratio first)
  bool refine = true;
  LsmOptions lsm = pair_lsm_options();
  // The window's shape model: automatic (choose_pair_shape in match_pair.cpp: quadratic where a sample of
  // the pair's matches shows the map curving within the window, else affine), affine, or quadratic.
  // lsm.quadratic is set from it (a value set there by hand is overridden).
  enum class Shape { automatic, affine, quadratic };
  Shape shape = Shape::automatic;
  // The window's size: chosen (window_size.hpp: lsm.taper and lsm.window are the base, larger sizes from
  // window_size_candidates() are tried on a sample of the pair's matches, only with the affine model and
  // a verified epipolar geometry), or lsm's as given. With a larger size chosen, a record whose
  // refinement fails on its content there is refined again at the base size (the same acceptance).
  bool choose_size = true;
  // With a larger size chosen, the records whose sigma there lies above this quantile of the pair's
  // sigmas, and those it failed on (refined at the base instead, or not at all), are refined at each
  // smaller size of window_size_candidates() (the base's shape model) and keep the one with the lowest
  // sigma (match_pair.cpp, step 5f). 1 or more: none (a failed record still falls back to the base).
  double recheck_quantile = 0.9;
  // Windows (odd, pixels) tried in turn where lsm.window's refinement failed on its content (drifted, low
  // correlation, imprecise, not converged, diverged, off the pair model); the first accepted with a sigma
  // within the median of the pair's first-window sigmas is kept. Empty:
  // none. Not where the window left the image (smaller windows 15 and 11 then, always).
  std::vector<int> retry_windows = {15, 31, 41};
  // A keypoint so near an image's edge that even the 11 px window leaves the image: the pair's window cut
  // to its pixels inside both images, where they hold at least this share of its taper's weight
  // (LsmOptions::edge_share; 0 = never, the match stays unrefined as out-of-image). Through tp-plan's
  // block the synthetic 12-view block of docs/blocks.md keeps its accuracy against the true terrain
  // (0.0344 m NMAD either way) once tp-refine's high-pass estimate compares its candidates over the same
  // views (multi_image_lsm.hpp): over each run's own views, the changed tracks had moved it to 1 px and
  // the block to 0.077 m.
  double edge_share = 0.4;
  bool keep_unrefined = true;     // a verified match whose refinement is rejected stays at its keypoint position
  double unrefined_sigma = 0.5;   // pixels: the least sigma given to such a match
  // Relative blur of the images before refinement (relative_blur.hpp: > 0 blurs image 1, < 0 image 2,
  // pixels); unset: estimated from the pair's matches.
  std::optional<double> blur;
  // Local-mean high-pass of both images before refinement (radiometric_highpass.hpp: Gaussian sigma in
  // pixels, 0 none); unset: chosen from the pair's matches.
  std::optional<double> highpass;
  std::string cache_dir;          // keypoint cache folder (keypoint_cache.hpp); empty = none
  // Region runs (match_region.hpp): only the verified matches whose image-1 keypoint lies in this
  // window [x0, x1) x [y0, y1) (pixel-centre coordinates) are refined and returned; the others gave
  // them their context (ratio test, mutual check, RANSAC) and are dropped before refinement.
  std::optional<std::array<double, 4>> window;
  long refine_tile = 256;         // rows of the image-1 bands refined one after the other (bounded memory)
  // The part of each image the refinement reaches (all of it in a whole run, about the window in a region
  // run) is read once and held when it has at most this many pixels (4096²: 64 MiB as float); a larger
  // one is read band by band on every pass, the estimates' samples window by window.
  long refine_hold_pixels = 4096L * 4096L;
  int threads = 1;
  // When set, refinement takes its current value for each band instead of `threads`: a pair matched
  // beside another job (match_every_pair) gets back the threads that job frees.
  const std::atomic<int>* live_threads = nullptr;
  bool progress = false;
};

// The window's shape model of a pair's refinement (PairMatchOptions::shape).
struct ShapeChoice {
  bool quadratic = false;
  double median_chi2 = NAN;  // over the sample: the curvature's significance (LsmResult::curvature_chi2)
  long samples = 0;          // matches whose quadratic stage measured it (0: given, or not estimated)
};

struct PairMatchStats {
  long keypoints1 = 0, keypoints2 = 0, putative = 0, verified = 0, gridded = 0, refined = 0;
  long retried = 0;  // of the refined: at a retry window (PairMatchOptions::retry_windows)
  long at_edge = 0;  // of the refined: with the window cut at an image's edge (PairMatchOptions::edge_share)
  long in_window = 0;                          // of the gridded ones, those in PairMatchOptions::window (all without one)
  double ransac_rms = 0;
  bool cached1 = false, cached2 = false;       // keypoints read from the cache
  bool guided = false;                         // the guided search ran (else the global one)
  GuidedMatchResult guide;                     // its figures (matches moved out)
  bool rpc_guided = false;                     // the search regions came from the RPCs
  RpcGuidedStats rpc;                          // their figures
  bool rpc_fallback = false;                   // the curves held no geometry: the coarse stage's was used
  double seconds[4] = {0, 0, 0, 0};             // wall time of detection, matching, verification, refinement
  long dropped[kLsmStatusCount] = {};          // by LsmStatus: refinement rejected, record dropped (keep_unrefined false)
  long unrefined[kLsmStatusCount] = {};        // by LsmStatus: refinement rejected, kept at the keypoint position
  double unrefined_sigma = 0;                  // the sigma those got
  RelativeBlur blur;                           // the relative blur the refinement used (relative_blur.hpp)
  HighpassChoice highpass;                     // the high-pass it used (radiometric_highpass.hpp)
  ShapeChoice shape;                           // the window's shape model it used (choose_pair_shape)
  WindowSizeChoice size;                       // the window's size it used (choose_pair_size)
  std::vector<WindowSize> smaller_sizes;       // the sizes below the chosen one (the base first; recheck_smaller_sizes)
  std::vector<long> at_smaller;                // of the refined: at each of them
  long rechecked = 0;                          // of those: the chosen size's sigma above recheck_sigma
  double recheck_quantile = 0, recheck_sigma = 0;  // that quantile of the chosen size's sigmas, and its value
  bool no_parallax = false;                    // verified by a 2-D affine map: the views have no parallax
  bool overlap = true;                         // false: too few verified matches, zero records
};

Matches match_pair(const ImageSource& a, const ImageSource& b, const PairMatchOptions& o, PairMatchStats* stats = nullptr);

// Why a pair came out with no verified matches (stats.overlap false), in words for the warning that
// says so: when the search regions came from the RPC models and their curves held no geometry, the
// models (their bias beyond the margin), the height range searched or the overlap; when the RPC curves
// gave nothing to the keypoints of image 1, the model of image 1; else the overlap.
std::string no_match_reason(const PairMatchStats& st, const PairMatchOptions& o);

// Why the RPC curves gave way to the images' own coarse stage (stats.rpc_fallback), in words that follow
// "the RPC epipolar curves of A and B": the heights searched (a --height-range that misses the terrain)
// or the models' bias beyond the margin.
std::string rpc_fallback_reason(const PairMatchStats& st, const PairMatchOptions& o);

// The same from keypoints already detected (detect_sift_cached with o.sift) of a and b; the pipeline
// from step 2 on. The descriptors are released once matched (shallow copies keep the caller's).
Matches match_keypoints(const ImageSource& a, const ImageSource& b, Keypoints K1, Keypoints K2, const PairMatchOptions& o,
                        PairMatchStats* stats = nullptr);

// Initial local map image 1 -> image 2 from two SIFT keypoints: (size2 / size1) R(angle2 - angle1),
// angles in OpenCV's convention (degrees, from +x towards +y in pixel coordinates).
Eigen::Matrix2d keypoint_affine(double size1, double angle1_deg, double size2, double angle2_deg);

}  // namespace tpkit
