// The size of a pair's least-squares window (lsm_refine.hpp: the Gaussian taper and the block around
// it), chosen from the pair's own matches. A larger window averages more pixels, so the refined position
// is less noisy; but the affine window estimates the map averaged over the window, and where the terrain
// curves within it (relief, a wall between roof and street) that average moves the position along the
// epipolar lines, where the heights are. Across them the terrain moves nothing (for affine views a
// point's parallax lies along its epipolar line), so a pair can see the bias: refine a sample of its
// matches at the base size and at a larger one, and compare the differences of the two positions along
// the epipolar lines with those across them. Without bias both are the same noise; with it the
// differences along them are wider. A larger size is kept where that ratio of spreads stays within
// max_ratio and its matches lie closer to their own epipolar geometry (epipolar_spread) than the size
// before, by min_gain (relative); the candidates are tried in order and the search stops at the first
// that fails. At each size the affine model is tried first, then the quadratic one, whose curvature
// terms take out the bias the larger window would see (its differences from the base then stay noise
// where the affine one's did not); the first of them kept is the size's, and where neither is the search
// stops. Set on truth (tp-synth, pairs' median error against the truth, px, base -> taper 5): relief
// 15 m, quadratic 0.0166 -> 0.0116, 0.0259 -> 0.0203, 0.0180 -> 0.0113 (ratios 0.85, 1.11, 0.69: kept);
// buildings, affine 0.041 -> 0.066, 0.048 -> 0.090, 0.039 -> 0.062 (ratios 2.02, 1.34, 1.56: refused).
//
// Conventions: taper (Gaussian sigma) and window (odd block size) in pixels of image 1; positions and
// spreads in pixels of image 2; epipolar_dir the direction of the epipolar lines in image 2 (any length).
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace tpkit {

constexpr double kWindowSizeMaxRatio = 1.3, kWindowSizeMinGain = 0.05;

struct WindowSize {
  double taper = 3;        // Gaussian sigma of the weights, pixels
  int window = 21;         // the block, pixels (odd)
  bool quadratic = false;  // the window's shape model (lsm_refine.hpp): affine or quadratic
  bool same_size(const WindowSize& o) const { return taper == o.taper && window == o.window; }
};

// What refining the sample at one size gave: row k the record's x1 y1 x2 y2 (image 2 refined), valid
// where ok[k]; the same records, in the same order, for every size.
struct WindowSizeSample {
  std::vector<char> ok;
  Eigen::MatrixX4d xy;
};

struct WindowSizeChoice {
  WindowSize size;  // the size chosen (the base when none was tried or none kept)
  struct Tried {
    WindowSize size;
    long common = 0;                 // records refined at the base, the size before and this one
    double ratio = NAN;              // spread of the differences from the base along / across the epipolar lines
    double spread_before = NAN;      // epipolar_spread of the size before (over the common records)
    double spread = NAN;             // and of this one
    bool kept = false;
  };
  std::vector<Tried> tried;
  long samples = 0;     // records in the sample (set by the caller)
  bool shapes = true;   // the candidates differ in the window's shape model too (pairs); false: in size alone
};

// 1.4826 x the median absolute deviation from the median (a robust standard deviation); NaN when empty.
double robust_spread(std::vector<double> v);

// The spread (1.4826 x the median absolute deviation) of the differences d along `dir` over their spread
// across it. NaN with fewer than 8 differences or no spread across.
double along_across_ratio(const std::vector<Eigen::Vector2d>& d, const Eigen::Vector2d& dir);

// Refines at `base`, then the candidates in order (grouped by size: affine, then quadratic) while a size
// keeps one (see above). refine(size) refines the same sample at that size and model.
WindowSizeChoice choose_window_size(const std::function<WindowSizeSample(const WindowSize&)>& refine, const WindowSize& base,
                                    const std::vector<WindowSize>& candidates, const Eigen::Vector2d& epipolar_dir,
                                    double max_ratio = kWindowSizeMaxRatio, double min_gain = kWindowSizeMinGain);

// The pair's candidates beyond the default window (taper 3 px, 21 px): taper 5 and 7 px, each block
// holding the pixels within lsm_refine's support (2.75 tapers) of its centre, affine then quadratic.
std::vector<WindowSize> window_size_candidates();

// A "# size:" header value: the size, then "(--window/--taper)" when given, `not_estimated` when no sample
// was measured, else what each size tried showed over the `sampled` ("sampled matches", "sampled tracks").
std::string describe_window_size(const WindowSizeChoice& c, bool given, const std::string& not_estimated,
                                 const std::string& sampled = "sampled matches", double max_ratio = kWindowSizeMaxRatio,
                                 double min_gain = kWindowSizeMinGain);

}  // namespace tpkit
