#include "tpkit/match/rpc_guided_matching.hpp"

#include <algorithm>
#include <Eigen/Dense>
#include <cmath>

#include "tpkit/core/error.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/rpc/epipolar_grid.hpp"

namespace tpkit {

void rpc_height_range(const RpcModel& a, const RpcModel& b, const RpcGuideOptions& r, double& h_lo, double& h_hi) {
  if (r.height_given) {
    if (!std::isfinite(r.h_lo) || !std::isfinite(r.h_hi) || !(r.h_lo < r.h_hi))
      throw UsageError("--height-range: LO must be below HI (metres above the ellipsoid)");
    h_lo = r.h_lo, h_hi = r.h_hi;
    return;
  }
  h_lo = std::max(a.height_min(), b.height_min());
  h_hi = std::min(a.height_max(), b.height_max());
  if (!(h_lo < h_hi))
    throw InputError("the RPC models' height ranges do not meet (" + format_number(a.height_min()) + ".." +
                     format_number(a.height_max()) + " m and " + format_number(b.height_min()) + ".." +
                     format_number(b.height_max()) + " m): give --height-range");
}

namespace {

// The chord of the epipolar curve of pixel (x, y) of image a in image b from height lo to hi.
constexpr int kMaxSamples = 64;  // heights along a curve (RpcGuideOptions::samples, clamped)
struct Chord {
  Eigen::Vector2d q0{0, 0}, q1{0, 0};
  double bend = 0;  // largest distance of the curve from the chord, pixels
  bool ok = false;
};

// The curve's points come from `grid` where it holds them (all of them), else from the models.
Chord chord_of(const RpcModel& a, const RpcModel& b, const EpipolarGrid& grid, double x, double y, double lo, double hi,
               int samples) {
  Chord c;
  Eigen::Vector2d curve[kMaxSamples];
  bool from_grid = true;
  for (int k = 0; k < samples && from_grid; ++k) from_grid = grid.point(x, y, lo + (hi - lo) * k / (samples - 1), curve[k]);
  if (!from_grid) {
    const auto exact = epipolar_curve(a, b, x, y, lo, hi, samples);
    if (exact.size() < static_cast<size_t>(samples)) return c;  // a height the model cannot localize
    for (int k = 0; k < samples; ++k) curve[k] = exact[static_cast<size_t>(k)].head<2>();
  }
  c.q0 = curve[0];
  c.q1 = curve[samples - 1];
  const Eigen::Vector2d d = c.q1 - c.q0;
  const double len = d.norm();
  if (len > 1e-9) {
    const Eigen::Vector2d n(d.y() / len, -d.x() / len);
    for (int k = 0; k < samples; ++k) c.bend = std::max(c.bend, std::abs(n.dot(curve[k] - c.q0)));
  }
  c.ok = true;
  return c;
}

SearchRegion region_of(const Chord& c, double along, double across) {
  SearchRegion r;
  if (!c.ok) return r;
  const Eigen::Vector2d d = c.q1 - c.q0;
  const double len = d.norm();
  r.u = len > 1e-9 ? Eigen::Vector2d(d / len) : Eigen::Vector2d(1, 0);
  r.a = c.q0 - along * r.u;
  r.length = len + 2 * along;
  r.band = across + c.bend;
  return r;
}

Keypoints subset(const Keypoints& K, const std::vector<int>& idx) {
  Keypoints out;
  out.desc = cv::Mat(static_cast<int>(idx.size()), K.desc.cols, K.desc.type());
  for (size_t k = 0; k < idx.size(); ++k) {
    out.kp.push_back(K.kp[static_cast<size_t>(idx[k])]);
    K.desc.row(idx[k]).copyTo(out.desc.row(static_cast<int>(k)));
  }
  return out;
}

}  // namespace

std::vector<SearchRegion> rpc_search_regions(const RpcModel& a, const RpcModel& b, const std::vector<cv::KeyPoint>& kp1,
                                             const std::vector<double>& h_lo, const std::vector<double>& h_hi,
                                             double along, double across, int samples, int threads, RpcGuidedStats* stats) {
  samples = std::clamp(samples, 2, kMaxSamples);
  // the curves' points interpolated in a grid of exact ones over the keypoints' box and heights
  // (epipolar_grid.hpp: checked to 1e-3 px), the models' own where the grid has none
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300, lo = 1e300, hi = -1e300;
  for (size_t i = 0; i < kp1.size(); ++i) {
    x0 = std::min(x0, static_cast<double>(kp1[i].pt.x)), x1 = std::max(x1, static_cast<double>(kp1[i].pt.x));
    y0 = std::min(y0, static_cast<double>(kp1[i].pt.y)), y1 = std::max(y1, static_cast<double>(kp1[i].pt.y));
    lo = std::min(lo, h_lo[i]), hi = std::max(hi, h_hi[i]);
  }
  EpipolarGridOptions go;
  go.max_nodes = static_cast<long>(kp1.size()) * samples / 4;  // the grid must save most of the localizations
  const EpipolarGrid grid(a, b, x0, y0, x1, y1, lo, hi, go, threads);
  // each keypoint's region straight from its chord (a 10000² image's 2 million chords held beside the
  // regions cost 97 MB at the run's peak); the statistics read the chords back from the regions
  std::vector<SearchRegion> out(kp1.size());
  parallel_for(kp1.size(), threads, [&](size_t i) {
    out[i] = region_of(chord_of(a, b, grid, kp1[i].pt.x, kp1[i].pt.y, h_lo[i], h_hi[i], samples), along, across);
  });
  double sum = 0;
  long n = 0;
  for (const SearchRegion& r : out) {
    if (r.length < 0) continue;  // no chord: a height the model cannot localize
    sum += r.length - 2 * along;
    ++n;
    if (stats) stats->max_bend = std::max(stats->max_bend, r.band - across);
  }
  if (stats) {
    stats->unlocalized = static_cast<long>(kp1.size()) - n;
    stats->mean_length = n > 0 ? sum / n : 0;
  }
  return out;
}

namespace {

// Step 1 within one margin: the strongest keypoints of image 1 matched in their curves' regions widened
// by `margin` pixels on every side (along and across), an affine F fitted to them; its inliers' heights
// (where along its chord each falls) and their offsets across the curves (the models' relative bias there).
struct Coarse {
  double margin = 0;
  long putative = 0, inliers = 0;
  bool ok = false;                       // enough inliers for a geometry
  std::vector<Eigen::Vector3d> heights;  // x1, y1, height (metres) of each inlier
  Eigen::Vector3d bias{0, 0, 0};         // across-curve offset, a plane in (x1, y1), pixels
  double bias_min = 0, bias_max = 0, bias_rms = 0;
  double metres_per_px = 0;              // along the curves (their mean chord length over the range)
};

Coarse coarse_geometry(const Keypoints& C1, const Keypoints& K2, const RpcModel& a, const RpcModel& b, double lo, double hi,
                       double margin, const DescriptorMatchOptions& desc, const GuidedMatchOptions& g,
                       const RpcGuideOptions& r, const AffineFundamentalRansac& ransac, int min_inliers, int threads) {
  Coarse c;
  c.margin = margin;
  const std::vector<double> clo(C1.kp.size(), lo), chi(C1.kp.size(), hi);
  RpcGuidedStats cs;
  const std::vector<SearchRegion> cr = rpc_search_regions(a, b, C1.kp, clo, chi, margin, margin, r.samples, threads, &cs);
  const RegionMatchResult coarse = match_in_regions(C1, K2, cr, desc, g.ratio_margin, threads);
  c.putative = static_cast<long>(coarse.matches.size());
  if (c.putative < std::max(min_inliers, AffineFundamental::MINIMUM_SAMPLES)) return c;
  Eigen::MatrixX4d xy(coarse.matches.size(), 4);
  for (size_t k = 0; k < coarse.matches.size(); ++k) {
    const auto &p = C1.kp[static_cast<size_t>(coarse.matches[k].i1)].pt, &q = K2.kp[static_cast<size_t>(coarse.matches[k].i2)].pt;
    xy.row(static_cast<Eigen::Index>(k)) << p.x, p.y, q.x, q.y;
  }
  const AffineFundamentalResult rr = ransac_affine_fundamental(xy, ransac);
  c.inliers = rr.ok ? rr.inliers : 0;
  if (!rr.ok || rr.inliers < min_inliers || !(cs.mean_length > 0)) return c;
  // the height of an inlier: where along its chord (linear in h) its image-2 position falls; its offset
  // across the chord: the models' bias there
  std::vector<Eigen::Index> in;
  std::vector<double> across;
  for (size_t k = 0; k < coarse.matches.size(); ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    if (!rr.inlier[row]) continue;
    const SearchRegion& R = cr[static_cast<size_t>(coarse.matches[k].i1)];
    const Eigen::Vector2d v = xy.row(row).tail<2>().transpose() - R.a;
    const double len = R.length - 2 * margin;
    const double t = len > 1e-9 ? (R.u.dot(v) - margin) / len : 0.5;
    c.heights.emplace_back(xy(row, 0), xy(row, 1), lo + t * (hi - lo));
    in.push_back(row);
    across.push_back(R.u.y() * v.x() - R.u.x() * v.y());
  }
  // the bias across the curves, a plane in x1 (shift and drift of the models)
  Eigen::MatrixX3d A(in.size(), 3);
  Eigen::VectorXd d(in.size());
  for (size_t q = 0; q < in.size(); ++q) {
    A.row(static_cast<Eigen::Index>(q)) << xy(in[q], 0), xy(in[q], 1), 1.0;
    d(static_cast<Eigen::Index>(q)) = across[q];
  }
  c.bias = A.colPivHouseholderQr().solve(d);
  const Eigen::VectorXd res = d - A * c.bias;
  c.bias_rms = std::sqrt(res.squaredNorm() / static_cast<double>(res.size()));
  c.bias_min = d.minCoeff(), c.bias_max = d.maxCoeff();
  c.metres_per_px = (hi - lo) / cs.mean_length;
  c.ok = true;
  return c;
}

}  // namespace

std::vector<DescriptorMatch> rpc_guided_match(const Keypoints& K1, const Keypoints& K2, long w1, long h1, const RpcModel& a,
                                              const RpcModel& b, const DescriptorMatchOptions& desc,
                                              const GuidedMatchOptions& g, const RpcGuideOptions& r,
                                              const AffineFundamentalRansac& ransac, int min_inliers, int threads,
                                              RpcGuidedStats* stats) {
  RpcGuidedStats st;
  double lo = 0, hi = 0;
  rpc_height_range(a, b, r, lo, hi);
  st.h_lo = lo, st.h_hi = hi;
  const size_t n1 = K1.kp.size();
  std::vector<double> cell_lo(n1, lo), cell_hi(n1, hi);
  Eigen::Vector3d bias(0, 0, 0);  // across-curve bias plane of step 1, pixels
  // 1. coarse: the strongest keypoints over the whole range, their heights from the F inliers. The
  // margin follows the bias the data show: from r.margin, four times wider while the F finds no geometry
  // or step 2's band around its inliers' offsets across the curves does not lie within the margin (a
  // margin that cuts into the offsets would bias the plane fitted to them), up to r.max_margin; the first
  // geometry that fits, else the one of most inliers (a wide margin over repeated texture may find none).
  st.coarse_margin = r.margin;
  if (!K1.kp.empty() && !K2.kp.empty()) {
    const std::vector<int> c1 = strongest_spread(K1.kp, g.coarse_keypoints, g.coarse_grid);
    const Keypoints C1 = subset(K1, c1);
    Coarse best, last;
    for (double m = r.margin;; m = std::min(4 * m, r.max_margin)) {
      last = coarse_geometry(C1, K2, a, b, lo, hi, m, desc, g, r, ransac, min_inliers, threads);
      const bool fits = last.ok && std::max(std::abs(last.bias_min), std::abs(last.bias_max)) + std::max(g.band, 3 * last.bias_rms) <= m;
      if (last.ok && (fits || !best.ok || last.inliers > best.inliers)) best = last;
      if (fits || !(m < r.max_margin) || !(m > 0)) break;
    }
    const Coarse& used = best.ok ? best : last;  // without a geometry: the widest margin tried
    st.coarse_margin = used.margin;
    st.coarse_putative = used.putative;
    st.coarse_inliers = used.inliers;
    if (best.ok) {
      bias = best.bias;
      st.bias_rms = best.bias_rms;
      st.bias_min = best.bias_min, st.bias_max = best.bias_max;
      const CellRanges ranges =
          cell_ranges(best.heights, w1, h1, g.coarse_grid, g.min_cell_samples, g.parallax_margin * best.metres_per_px);
      st.narrowed = true;
      st.cell_h_lo = 1e300, st.cell_h_hi = -1e300;
      for (size_t c = 0; c < ranges.lo.size(); ++c)
        st.cell_h_lo = std::min(st.cell_h_lo, ranges.lo[c]), st.cell_h_hi = std::max(st.cell_h_hi, ranges.hi[c]);
      for (size_t i = 0; i < n1; ++i) {
        const size_t c = ranges.cell(K1.kp[i].pt.x, K1.kp[i].pt.y);
        cell_lo[i] = ranges.lo[c], cell_hi[i] = ranges.hi[c];
      }
    }
  }
  // 2. every keypoint in the region of its cell's heights
  // (narrowed: no margin along the curves beyond the cells' ranges, the measured bias removed across
  // them, and the affine guided search's band, or 3 x the RMS the bias plane leaves if that is wider;
  // else the widest margin step 1 tried)
  const double along = st.narrowed ? 0.0 : st.coarse_margin, across = st.narrowed ? std::max(g.band, 3 * st.bias_rms) : st.coarse_margin;
  std::vector<SearchRegion> regions = rpc_search_regions(a, b, K1.kp, cell_lo, cell_hi, along, across, r.samples, threads, &st);
  if (st.narrowed)
    for (size_t i = 0; i < n1; ++i)
      regions[i].a += (bias(0) * K1.kp[i].pt.x + bias(1) * K1.kp[i].pt.y + bias(2)) * Eigen::Vector2d(regions[i].u.y(), -regions[i].u.x());
  RegionMatchResult res = match_in_regions(K1, K2, regions, desc, g.ratio_margin, threads);
  st.candidates_per_query = res.candidates_per_query;
  if (stats) *stats = st;
  return std::move(res.matches);
}

}  // namespace tpkit
