#include "tpkit/match/match_pair.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <memory>
#include <numeric>
#include <opencv2/calib3d.hpp>

#include "tpkit/match/affine_fundamental.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/match/keypoint_cache.hpp"
#include "tpkit/match/opencv_memory.hpp"
#include "tpkit/match/radiometric_highpass.hpp"
#include "tpkit/match/relative_blur.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/match/rpc_guided_matching.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tool_support.hpp"

namespace tpkit {

Eigen::Matrix2d keypoint_affine(double size1, double angle1_deg, double size2, double angle2_deg) {
  double s = size1 > 0 && size2 > 0 ? size2 / size1 : 1.0;
  double a = (angle2_deg - angle1_deg) * M_PI / 180.0;
  if (angle1_deg < 0 || angle2_deg < 0) a = 0;  // no orientation
  Eigen::Matrix2d R;
  R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  return s * R;
}


Matches match_pair(const ImageSource& a, const ImageSource& b, const PairMatchOptions& o, PairMatchStats* stats) {
  const auto t0 = std::chrono::steady_clock::now();
  Keypoints K1, K2;
  bool c1 = false, c2 = false;
  {
    std::unique_ptr<Progress> p1, p2;
    if (o.progress) p1 = std::make_unique<Progress>("detect " + a.path, (long)tile_grid(a.info.width, a.info.height, o.sift.tile, o.sift.overlap).size());
    K1 = detect_sift_cached(a, o.sift, o.threads, o.cache_dir, p1.get(), &c1);
    if (p1) p1->done();
    if (o.progress) p2 = std::make_unique<Progress>("detect " + b.path, (long)tile_grid(b.info.width, b.info.height, o.sift.tile, o.sift.overlap).size());
    K2 = detect_sift_cached(b, o.sift, o.threads, o.cache_dir, p2.get(), &c2);
    if (p2) p2->done();
  }
  Matches M = match_keypoints(a, b, std::move(K1), std::move(K2), o, stats);
  if (stats) {
    stats->cached1 = c1;
    stats->cached2 = c2;
    stats->seconds[0] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() -
                        stats->seconds[1] - stats->seconds[2] - stats->seconds[3];
  }
  return M;
}

// The stages of match_keypoints(). Conventions: image 1 is the template side; a DescriptorMatch
// holds indices into K1 (i1) and K2 (i2); positions are pixel-centre coordinates (x = column, y = row);
// `ver` lists indices into the putative matches.
namespace {

// 2. Putative matches: along the RPC epipolar curves when both models are given, else (or when the
// curves held no geometry and the caller allows it) along the coarse stage's epipolar band, else over
// all descriptors.
std::vector<DescriptorMatch> putative_matches(const ImageSource& a, const Keypoints& K1, const Keypoints& K2,
                                              const PairMatchOptions& o, const AffineFundamentalRansac& cr, PairMatchStats& st) {
  std::vector<DescriptorMatch> put;
  if (o.rpc1 && o.rpc2) {
    put = rpc_guided_match(K1, K2, a.info.width, a.info.height, *o.rpc1, *o.rpc2, o.desc, o.guide, o.rpc_guide, cr,
                           o.min_inliers, o.threads, &st.rpc);
    st.rpc_guided = true;
  }
  const bool rpc_failed = st.rpc_guided && !st.rpc.narrowed;
  if (o.guided && (!st.rpc_guided || (rpc_failed && !o.rpc_only))) {
    GuidedMatchResult g = guided_match(K1, K2, a.info.width, a.info.height, o.desc, o.guide, cr, o.min_inliers, o.threads);
    if (g.ok || !st.rpc_guided) {
      st.rpc_fallback = st.rpc_guided && g.ok;
      if (st.rpc_fallback) st.rpc_guided = false;
      st.guided = g.ok;
      st.guide = std::move(g);
      put = std::move(st.guide.matches);
      st.guide.matches.clear();
    }
  }
  if (!st.guided && !st.rpc_guided) put = match_descriptors(K1.desc, K2.desc, o.desc);
  st.putative = static_cast<long>(put.size());
  return put;
}

// 3. Verification by the affine F (RANSAC); when that finds no model, by a 2-D affine map (zero
// parallax: views that are identical or nearly so map onto each other by a plane affinity, and every
// affine F that contains it fits them). Returns the verified putative indices; `rr` is the F fit.
std::vector<size_t> verify_matches(const std::vector<DescriptorMatch>& put, const Keypoints& K1, const Keypoints& K2,
                                   const PairMatchOptions& o, AffineFundamentalResult& rr, PairMatchStats& st) {
  Eigen::MatrixX4d xy(put.size(), 4);
  for (size_t i = 0; i < put.size(); ++i) {
    const auto &k1 = K1.kp[put[i].i1], &k2 = K2.kp[put[i].i2];
    xy.row(static_cast<Eigen::Index>(i)) << k1.pt.x, k1.pt.y, k2.pt.x, k2.pt.y;
  }
  AffineFundamentalRansac ro;
  ro.threshold = o.ransac_threshold;
  ro.max_iterations = o.ransac_iterations;
  ro.seed = o.seed;
  rr = ransac_affine_fundamental(xy, ro);
  std::vector<size_t> ver;
  if (rr.ok && rr.inliers >= o.min_inliers)
    for (size_t i = 0; i < put.size(); ++i)
      if (rr.inlier[i]) ver.push_back(i);
  if (ver.empty() && put.size() >= 3) {
    std::vector<cv::Point2f> p1(put.size()), p2(put.size());
    for (size_t i = 0; i < put.size(); ++i) p1[i] = K1.kp[put[i].i1].pt, p2[i] = K2.kp[put[i].i2].pt;
    std::vector<uchar> in;
    const cv::Mat A = cv::estimateAffine2D(p1, p2, in, cv::RANSAC, o.ransac_threshold,
                                           static_cast<size_t>(std::max(1, o.ransac_iterations)), 0.999, 10);
    const long n_in = static_cast<long>(std::count(in.begin(), in.end(), uchar(1)));
    if (!A.empty() && n_in >= o.min_inliers) {
      double ss = 0;
      for (size_t i = 0; i < put.size(); ++i)
        if (in[i]) {
          ver.push_back(i);
          const double ex = A.at<double>(0, 0) * p1[i].x + A.at<double>(0, 1) * p1[i].y + A.at<double>(0, 2) - p2[i].x;
          const double ey = A.at<double>(1, 0) * p1[i].x + A.at<double>(1, 1) * p1[i].y + A.at<double>(1, 2) - p2[i].y;
          ss += ex * ex + ey * ey;
        }
      st.no_parallax = true;
      st.ransac_rms = std::sqrt(ss / static_cast<double>(ver.size()));
    }
  }
  st.verified = static_cast<long>(ver.size());
  if (!st.no_parallax) st.ransac_rms = rr.ok ? rr.rms : 0;
  if (ver.empty()) st.overlap = false;
  return ver;
}

// 4. Grid thinning: the best-ratio matches of each cell of a grid over image 1.
void thin_to_grid(std::vector<size_t>& ver, const std::vector<DescriptorMatch>& put, const Keypoints& K1, const ImageSource& a,
                  const PairMatchOptions& o) {
  if (o.grid <= 0 || ver.empty()) return;
  std::vector<cv::Point2f> pts;
  std::vector<float> score;
  for (size_t i : ver) {
    pts.push_back(K1.kp[put[i].i1].pt);
    score.push_back(put[i].ratio);
  }
  std::vector<size_t> keep = grid_select(pts, score, a.info.width, a.info.height, o.grid, o.per_cell);
  std::vector<size_t> v2;
  for (size_t k : keep) v2.push_back(ver[k]);
  ver.swap(v2);
}

// 4b. Region runs: only the matches whose image-1 keypoint lies in the window go on (the others
// gave the window's matches their context and are not refined).
void keep_in_window(std::vector<size_t>& ver, const std::vector<DescriptorMatch>& put, const Keypoints& K1,
                    const std::array<double, 4>& w) {
  std::vector<size_t> v2;
  for (size_t i : ver) {
    const cv::Point2f p = K1.kp[put[i].i1].pt;
    if (p.x >= w[0] && p.x < w[2] && p.y >= w[1] && p.y < w[3]) v2.push_back(i);
  }
  ver.swap(v2);
}

struct Rec {
  long long id1, id2;
  double x1, y1, x2, y2, kx2, ky2, sigma, corr;
  bool ok;           // (x2, y2) is the accepted LSM position (or there was no refinement)
  LsmStatus status;  // why not, when refined
  bool retried = false;  // refined at one of PairMatchOptions::retry_windows after the first window failed
  // refined at a size below the pair's (PairMatchOptions::choose_size): -1 none, else the index in
  // smaller_sizes() (0 the base), after the pair's size failed on its content or gave a sigma in the
  // pair's upper tail (recheck_smaller_sizes)
  int smaller = -1;
  bool rechecked = false;  // of those: the pair's size had been accepted, with a sigma in the upper tail
  bool at_edge = false;    // refined with its window cut at an image's edge (PairMatchOptions::edge_share)
  double curvature_chi2 = NAN;  // LsmResult::curvature_chi2 (the shape estimate's sample)
};

// The pixels the refinement reads. The blur and high-pass estimates refine samples of the records a few
// times over, then every record is refined, each pass band by band. Where the part of an image that the
// records reach (the whole image in a whole run, about the window in a region run) has at most
// o.refine_hold_pixels (4096²: 64 MiB as float), it is read once and every pass cuts its bands from
// memory; a larger one is read band by band on every pass (bounded memory), but the estimates' passes
// read only the windows of their samples' records, all once (windows(): on a 10000² pair the refinement stage,
// whose two estimates took 9.7 s of its 39.4, now takes 32.2 s). The estimates refine each sampled
// record on its own window, cut from the held pixels or from windows().
struct PixelRect {
  long x0, y0, w, h;
};
class RefinePixels {
 public:
  // Holds need[i] of image i when it has at most max_pixels pixels.
  RefinePixels(const ImageSource& a, const ImageSource& b, const PixelRect (&need)[2], long max_pixels) : src_{&a, &b} {
    held_all_ = true;
    for (int i = 0; i < 2; ++i) {
      const PixelRect& r = need[i];
      if (static_cast<double>(r.w) * static_cast<double>(r.h) <= static_cast<double>(max_pixels))
        held_[i].push_back(read_valid_region(*src_[i], r.x0, r.y0, r.w, r.h));
      else
        held_all_ = false;
    }
  }
  // Whether every region the refinement asks for is in memory.
  bool held() const { return held_all_; }
  const ImageSource& source(int i) const { return *src_[i]; }
  // The same pixels plus the regions rects[i] of each image not held (read band by band of `rows` rows,
  // each band once; the bands decoded side by side on `threads` workers: the estimates' samples spread
  // over the whole images, and decoding a 10000² pair's two deflate images took 2.4 s on one thread).
  RefinePixels windows(const std::vector<PixelRect> (&rects)[2], long rows, int threads) const {
    struct Band {
      int image;
      size_t k0, k1;  // its rects in sorted[image]
      long x0, y0, x1, y1;
    };
    std::vector<PixelRect> sorted[2];
    std::vector<Band> bands;
    for (int i = 0; i < 2; ++i) {
      if (!held_[i].empty()) continue;
      std::vector<PixelRect>& r = sorted[i];
      r = rects[i];
      std::sort(r.begin(), r.end(), [](const PixelRect& p, const PixelRect& q) { return p.y0 < q.y0; });
      for (size_t k0 = 0; k0 < r.size();) {
        size_t k1 = k0;
        long x0 = r[k0].x0, x1 = r[k0].x0 + r[k0].w, y1 = r[k0].y0 + r[k0].h;
        while (k1 < r.size() && r[k1].y0 < r[k0].y0 + rows) {
          x0 = std::min(x0, r[k1].x0), x1 = std::max(x1, r[k1].x0 + r[k1].w), y1 = std::max(y1, r[k1].y0 + r[k1].h);
          ++k1;
        }
        bands.push_back({i, k0, k1, x0, r[k0].y0, x1, y1});
        k0 = k1;
      }
    }
    std::vector<std::vector<Raster>> cut(bands.size());
    parallel_for(bands.size(), std::max(1, threads), [&](size_t b) {
      const Band& B = bands[b];
      const Raster band = read_valid_region(*src_[B.image], B.x0, B.y0, B.x1 - B.x0, B.y1 - B.y0);
      for (size_t k = B.k0; k < B.k1; ++k) {
        const PixelRect& r = sorted[B.image][k];
        cut[b].push_back(crop_region(band, r.x0, r.y0, r.w, r.h));
      }
    });
    RefinePixels w = *this;
    for (size_t b = 0; b < bands.size(); ++b)
      for (Raster& r : cut[b]) w.held_[bands[b].image].push_back(std::move(r));
    return w;
  }
  // read_valid_region of image i (0: a, 1: b): cut from a held raster that holds it, else read
  Raster region(int i, long x0, long y0, long w, long h) const {
    // the part inside the image, as read_valid_region clips it
    const long cx0 = std::max(0L, x0), cy0 = std::max(0L, y0);
    const long cx1 = std::min(src_[i]->info.width, x0 + w), cy1 = std::min(src_[i]->info.height, y0 + h);
    for (const Raster& r : held_[i])
      if (r.x0 <= cx0 && r.y0 <= cy0 && r.x0 + r.width >= cx1 && r.y0 + r.height >= cy1) return crop_region(r, x0, y0, w, h);
    return read_valid_region(*src_[i], x0, y0, w, h);
  }

 private:
  const ImageSource* src_[2];
  std::vector<Raster> held_[2];
  bool held_all_ = false;
};

// The widest filter support the estimates try, pixels: blur up to 3 px in either image and high-pass up
// to 2 px (relative_blur.hpp, radiometric_highpass.hpp), 3-sigma supports 9 and 6 px.
constexpr double kWidestFilterSupport = 15;

// Records refined together, and the image regions that hold their windows (plus the interpolation
// support, the allowed drift and the filters' 3-sigma supports e1, e2 in images 1 and 2).
struct RefineGroup {
  std::vector<size_t> js;
  PixelRect a, b;
};
RefineGroup refine_group(std::vector<size_t> js, const std::vector<Rec>& recs, const std::vector<Eigen::Matrix2d>& A0,
                         const PairMatchOptions& o, double e1, double e2) {
  int widest = o.lsm.window;
  for (int w : o.retry_windows) widest = std::max(widest, w);
  if (o.choose_size)
    for (const WindowSize& w : window_size_candidates()) widest = std::max(widest, w.window);
  const int h = widest / 2;
  double ax0 = 1e300, ay0 = 1e300, ax1 = -1e300, ay1 = -1e300, bx0 = 1e300, by0 = 1e300, bx1 = -1e300, by1 = -1e300;
  for (size_t j : js) {
    const Rec& r = recs[j];
    const double ext1 = h * std::sqrt(2.0) + 3;
    const double ext2 = h * std::sqrt(2.0) * A0[j].norm() * 1.5 + o.lsm.max_shift * 3 + 6;
    ax0 = std::min(ax0, r.x1 - ext1), ax1 = std::max(ax1, r.x1 + ext1);
    ay0 = std::min(ay0, r.y1 - ext1), ay1 = std::max(ay1, r.y1 + ext1);
    bx0 = std::min(bx0, r.kx2 - ext2), bx1 = std::max(bx1, r.kx2 + ext2);
    by0 = std::min(by0, r.ky2 - ext2), by1 = std::max(by1, r.ky2 + ext2);
  }
  ax0 -= e1, ay0 -= e1, ax1 += e1, ay1 += e1, bx0 -= e2, by0 -= e2, bx1 += e2, by1 += e2;
  auto rect = [](double x0, double y0, double x1, double y1) {
    return PixelRect{static_cast<long>(std::floor(x0)), static_cast<long>(std::floor(y0)), static_cast<long>(std::ceil(x1 - x0)) + 2,
                     static_cast<long>(std::ceil(y1 - y0)) + 2};
  };
  return {std::move(js), rect(ax0, ay0, ax1, ay1), rect(bx0, by0, bx1, by1)};
}

// A refinement that failed on what the window holds (not on where it lies: out of the image, nodata).
bool failed_on_content(LsmStatus s) {
  return s == LsmStatus::Drifted || s == LsmStatus::LowCorrelation || s == LsmStatus::Imprecise || s == LsmStatus::NotConverged ||
         s == LsmStatus::Diverged || s == LsmStatus::OffEpipolar;
}

// 5. Least-squares matching of every record, image 1 in bands of refine_tile rows, one after the
// other: each band's region of image 1 and the region of image 2 its windows reach are read once (a
// strip-stored file is decoded about once in all), and the band's points are refined in parallel while
// the next band's regions are read. A band whose image-2 region would be too large (strong rotation
// between the images) is split along x until it fits. With `per_record`, each record is a group of its
// own and the groups are refined in parallel (the estimates' samples, their windows cut from the pixels
// px holds or read by px.windows(): filtering whole bands for a few windows each costs more than the
// refinement; a 2500² region job's two estimates took 0.18 s in bands, 0.05 s window by window). A0
// holds each record's initial local map (keypoint_affine). With `F`, a refined position farther than
// `max_residual` pixels (R^4) from the verified pair model is rejected (OffEpipolar): the keypoint
// match passed that test, so the refinement moved it off the geometry.
// With `base` (a larger size chosen: choose_pair_size), a record whose refinement at lsm's size fails on
// its content is refined again at base's (a change between the dates inside the larger window). With
// `cut_edges` (the final pass, not the estimates' samples), a record whose windows all leave the image
// gets lsm's window cut to its pixels inside both images (PairMatchOptions::edge_share).
void refine_records(const RefinePixels& px, std::vector<Rec>& recs, const std::vector<Eigen::Matrix2d>& A0,
                    const LsmOptions& lsm, const PairMatchOptions& o, const AffineFundamental* F, double max_residual,
                    double blur, double highpass, bool progress, bool per_record = false, double retry_max_sigma = 0,
                    const LsmOptions* base = nullptr, bool cut_edges = false) {
  const bool retry = retry_max_sigma > 0;
  // the blur's and the local mean's support (3 sigma) join the regions so that the windows see full kernels
  const double eh = highpass > 0 ? std::ceil(3 * highpass) : 0;
  const double e1 = (blur > 0 ? std::ceil(3 * blur) : 0) + eh, e2 = (blur < 0 ? std::ceil(-3 * blur) : 0) + eh;
  // live_threads: what the refinement may use now (read again for every band)
  auto threads = [&] { return o.live_threads ? std::max(1, o.live_threads->load()) : o.threads; };
  // the records of a group, refined on the group's pixels
  auto refine = [&](const RefineGroup& G, const std::pair<Raster, Raster>& R, size_t q0, size_t q1) {
    for (size_t q = q0; q < q1; ++q) {
      Rec& r = recs[G.js[q]];
      // one attempt with a window of `win` pixels (the taper in proportion), held to the verified pair model
      auto attempt = [&](int win, const LsmOptions* other = nullptr) {
        const LsmOptions& size = other ? *other : lsm;
        LsmOptions opt = size;
        if (win != size.window) {
          opt.window = win;
          opt.taper = size.taper * win / size.window;
        }
        LsmResult L = lsm_refine(R.first, R.second, {r.x1, r.y1}, {r.kx2, r.ky2}, A0[G.js[q]], opt);
        if (L.ok() && F && !(std::abs(F->residual(r.x1, r.y1, L.p2.x(), L.p2.y())) <= max_residual)) L.status = LsmStatus::OffEpipolar;
        return L;
      };
      LsmResult L;
      if (retry) {
        // a second pass over records whose first window failed on its content (images of different dates:
        // a shadow, a car, a turned field inside it pulled the fit away, left too little correlation or too
        // little precision): the retry windows in turn, a smaller one leaving more of the change out, a larger
        // one holding more texture; the first that passes every test with a sigma within retry_max_sigma
        // (the pair's own precision: the median of the first pass's) is kept. A failed record keeps
        // its first status.
        for (int win : o.retry_windows) {
          if (win == lsm.window) continue;
          L = attempt(win);
          if (L.ok() && L.sigma <= retry_max_sigma) break;
        }
        if (!(L.ok() && L.sigma <= retry_max_sigma)) continue;
        r.retried = true;
      } else {
        L = attempt(lsm.window);
        // a window that leaves the image (a keypoint near its edge) or meets nodata: smaller windows, the
        // taper in proportion (their sigma says what the fewer pixels give); on the synthetic default
        // scene this refines 2.6% more of pair 1-2's verified matches (out-of-image 253 -> 45)
        for (int win : {15, 11}) {
          if (!(L.status == LsmStatus::OutOfImage || L.status == LsmStatus::Invalid) || win >= lsm.window) continue;
          L = attempt(win);
        }
        // a keypoint within a few pixels of an edge: the pair's window cut to its pixels inside both images,
        // then, where it failed and a larger size was chosen, the base's
        if (L.status == LsmStatus::OutOfImage && cut_edges && o.edge_share > 0)
          for (const LsmOptions* size : {&lsm, base}) {
            if (!size || (size == base && L.ok())) continue;
            LsmOptions cut = *size;
            cut.edge_share = o.edge_share;
            const LsmResult Lc = attempt(size->window, &cut);
            if (Lc.status == LsmStatus::OutOfImage) continue;
            L = Lc, r.at_edge = Lc.ok();
            if (Lc.ok() && size == base) r.smaller = 0;
          }
        if (base && failed_on_content(L.status)) {
          const LsmResult Lb = attempt(base->window, base);
          if (Lb.ok()) L = Lb, r.smaller = 0;
        }
      }
      r.ok = L.ok();
      r.status = L.status;
      r.corr = std::isfinite(L.corr) ? L.corr : 0;
      r.curvature_chi2 = L.curvature_chi2;
      if (r.ok) {
        r.x2 = L.p2.x();
        r.y2 = L.p2.y();
        r.sigma = L.sigma;
      }
    }
  };
  // a group's regions, read and filtered
  auto load = [&](const RefineGroup& G) {
    std::pair<Raster, Raster> R{px.region(0, G.a.x0, G.a.y0, G.a.w, G.a.h), px.region(1, G.b.x0, G.b.y0, G.b.w, G.b.h)};
    if (blur > 0) blur_raster(R.first, blur);
    if (blur < 0) blur_raster(R.second, -blur);
    highpass_raster(R.first, highpass);
    highpass_raster(R.second, highpass);
    return R;
  };
  std::unique_ptr<Progress> pr;
  if (progress) pr = std::make_unique<Progress>("refine", static_cast<long>(recs.size()));
  if (per_record) {
    parallel_for(recs.size(), threads(), [&](size_t j) {
      const RefineGroup G = refine_group({j}, recs, A0, o, e1, e2);
      refine(G, load(G), 0, 1);
    });
    if (pr) pr->done();
    return;
  }
  const long B = std::max(16L, o.refine_tile);
  std::vector<std::vector<size_t>> bands(static_cast<size_t>((px.source(0).info.height + B - 1) / B) + 1);
  for (size_t j = 0; j < recs.size(); ++j)
    bands[std::clamp<size_t>(static_cast<size_t>(std::max(0.0, recs[j].y1 + 0.5) / B), 0, bands.size() - 1)].push_back(j);
  const double max_area = 64.0 * 1024 * 1024;  // pixels of an image-2 region (256 MB as float)
  // the groups: the bands, split along x where image 2's region would be too large
  std::vector<RefineGroup> groups;
  std::function<void(std::vector<size_t>&)> plan = [&](std::vector<size_t>& js) {
    if (js.empty()) return;
    RefineGroup G = refine_group(js, recs, A0, o, e1, e2);
    if (static_cast<double>(G.b.w) * static_cast<double>(G.b.h) > max_area && js.size() > 1) {
      std::sort(js.begin(), js.end(), [&](size_t p, size_t q) { return recs[p].x1 < recs[q].x1 || (recs[p].x1 == recs[q].x1 && p < q); });
      std::vector<size_t> lo(js.begin(), js.begin() + static_cast<long>(js.size() / 2)), hi(js.begin() + static_cast<long>(js.size() / 2), js.end());
      plan(lo);
      plan(hi);
      return;
    }
    groups.push_back(std::move(G));
  };
  for (auto& js : bands) plan(js);
  // few records a group (the estimates' samples: 200 or 300 over the image's bands): the groups side by
  // side, each read, filtered and refined on one thread, where splitting a group of a few dozen records
  // over the threads left them waiting on its reading and filtering (Marseille pair 1-2 at 2 threads:
  // the estimates took a quarter of the refinement stage)
  if (groups.size() > 1 && recs.size() < 256 * groups.size()) {
    parallel_for(groups.size(), threads(), [&](size_t g) {
      refine(groups[g], load(groups[g]), 0, groups[g].js.size());
      if (pr) pr->add(static_cast<long>(groups[g].js.size()));
    });
    if (pr) pr->done();
    return;
  }
  // the next group's regions are read on their own thread (or, where none can start, when they are needed)
  std::future<std::pair<Raster, Raster>> next;
  if (!groups.empty()) next = std::async(std::launch::async | std::launch::deferred, load, std::cref(groups[0]));
  for (size_t g = 0; g < groups.size(); ++g) {
    const std::pair<Raster, Raster> R = next.get();
    if (g + 1 < groups.size()) next = std::async(std::launch::async | std::launch::deferred, load, std::cref(groups[g + 1]));
    const size_t n = groups[g].js.size();
    const int t = threads();
    // chunks of up to 64 points, at least four per thread: a group of a few dozen would otherwise run on
    // one thread
    const size_t chunk = std::clamp<size_t>(n / (4 * static_cast<size_t>(t)), 1, 64);
    parallel_for((n + chunk - 1) / chunk, t, [&](size_t c) { refine(groups[g], R, c * chunk, std::min(n, (c + 1) * chunk)); });
    if (pr) pr->add(static_cast<long>(n));
  }
  if (pr) pr->done();
}

// The records the estimates refine: up to `want` spread evenly over the list (every k-th).
std::vector<size_t> sample_indices(size_t n, size_t want) {
  std::vector<size_t> idx;
  const size_t m = std::min(n, want);
  for (size_t k = 0; k < m; ++k) idx.push_back(k * n / m);
  return idx;
}
// the size's sample is larger: the ratio of two robust spreads over n records varies by about 2 / sqrt(n)
constexpr size_t kBlurSample = 200, kHighpassSample = 300, kSizeSample = 1000;

// A sample of the records, with their initial maps.
struct RecordSample {
  std::vector<Rec> recs;
  std::vector<Eigen::Matrix2d> A0;
};
RecordSample sample_records(const std::vector<Rec>& recs, const std::vector<Eigen::Matrix2d>& A0, size_t want) {
  RecordSample s;
  for (size_t j : sample_indices(recs.size(), want)) {
    s.recs.push_back(recs[j]);
    s.A0.push_back(A0[j]);
  }
  return s;
}

// The pixels of the estimates' samples where px does not hold them (none when it does, or when no
// estimate runs): the windows of their records (refine_group with the widest filter supports), read
// once for all.
std::optional<RefinePixels> estimate_pixels(const RefinePixels& px, const std::vector<Rec>& recs, const std::vector<Eigen::Matrix2d>& A0,
                                            const PairMatchOptions& o) {
  const bool none = o.blur && o.highpass && o.shape != PairMatchOptions::Shape::automatic && !o.choose_size;
  if (px.held() || none || recs.size() < 50) return std::nullopt;
  std::vector<size_t> idx = sample_indices(recs.size(), kBlurSample);
  for (size_t want : {kHighpassSample, kSizeSample}) {
    const std::vector<size_t> more = sample_indices(recs.size(), want);
    idx.insert(idx.end(), more.begin(), more.end());
  }
  std::sort(idx.begin(), idx.end());
  idx.erase(std::unique(idx.begin(), idx.end()), idx.end());
  std::vector<PixelRect> rects[2];
  for (size_t j : idx) {
    const RefineGroup G = refine_group({j}, recs, A0, o, kWidestFilterSupport, kWidestFilterSupport);
    rects[0].push_back(G.a);
    rects[1].push_back(G.b);
  }
  return px.windows(rects, std::max(16L, o.refine_tile), o.live_threads ? std::max(1, o.live_threads->load()) : o.threads);
}

// 5b. The records whose first window failed on its content, again at the retry windows (refine_records'
// second pass), accepted only with a sigma within the median of the pair's first-pass sigmas: a retry adds
// matches as precise as the pair's typical one, not the imprecise ones its first window rightly refused.
// Measured against truth: on the Jacksonville block (twelve crops, lidar DSM) every looser bound bought its
// refined matches with precision (flat ground NMAD 0.332 m without retries, 0.336 at the median, 0.337 at
// the 75th percentile, 0.345 at the 90th; at --max-sigma 48 Marseille triplets landed 0.5 px off the
// trifocal fit). At the median: the 66 pairs' refined share 90.9% -> 92.0% (the least pair's 85.3% ->
// 87.3%), each file's RMS distance to the RPC epipolar curves over all its matches level or lower; on the
// Marseille triplet 23 to 29 more per pair, the trifocal fit over its inliers unchanged (0.106 px).
void retry_failed_records(const RefinePixels& px, std::vector<Rec>& recs, const std::vector<Eigen::Matrix2d>& A0, const LsmOptions& lsm,
                          const PairMatchOptions& o, const AffineFundamental* F, double blur, double highpass) {
  if (o.retry_windows.empty()) return;
  std::vector<double> sig;
  std::vector<size_t> failed;
  for (size_t k = 0; k < recs.size(); ++k) {
    const Rec& r = recs[k];
    if (r.ok) {
      sig.push_back(r.sigma);
      continue;
    }
    if (failed_on_content(r.status)) failed.push_back(k);
  }
  if (failed.empty() || sig.size() < 10) return;
  const size_t q = sig.size() / 2;
  std::nth_element(sig.begin(), sig.begin() + static_cast<long>(q), sig.end());
  const double bound = std::min(sig[q], lsm.max_sigma);
  std::vector<Rec> sub;
  std::vector<Eigen::Matrix2d> subA;
  for (size_t k : failed) {
    sub.push_back(recs[k]);
    subA.push_back(A0[k]);
  }
  refine_records(px, sub, subA, lsm, o, F, o.ransac_threshold, blur, highpass, false, false, bound);
  for (size_t i = 0; i < failed.size(); ++i) recs[failed[i]] = sub[i];
}

// 5f. A pair's size is chosen for most of its matches; where the terrain or a change between the dates
// inside the larger window defeats it for one match, a smaller window may follow it better. The records
// whose refinement at the chosen size gave a sigma above o.recheck_quantile of the pair's (their fit's
// residuals tell that the window holds what its model cannot follow), and those the chosen size failed
// on (refined at the base instead, or not at all), are refined again at every smaller size of the
// pair's ladder (smaller_sizes(): the base and the candidates between, the base's shape model) and keep
// the refinement with the lowest sigma: the size that predicts the least error for this match (the
// adaptive window of Kanade and Okutomi, 1994, among the pair's sizes), a calibrated sigma at each
// size (lsm_refine.hpp). Nothing is lost: a record keeps what it had where no smaller size does better.
// A quantile of 1 or more turns the step off (a failed record then has the base size alone).
// Measured (2026-12-07): La Reunion (taper 7 px quadratic chosen) 6476 refined at 0.1650 px RMS from
// the RPC epipolar curves (an affine bias per image removed) -> 6479 at 0.1595 (over every record 0.188
// -> 0.182); the 66 Jacksonville pairs 93.5 -> 93.9% refined, the block's ground points on flat ground
// 0.279 m NMAD from the lidar over 5702 -> 5716 points, the pairwise product's 0.346 m over 5760 ->
// 0.338 m over 5774; the Marseille triplet's ML fit 0.0866 -> 0.0874 px, its transfer 0.281 -> 0.284 px
// RMS (a little worse); tp-synth relief 15 m (taper 7 quadratic) triplets' views 2+3 0.0157 / 0.0392 ->
// 0.0158 / 0.0392 px; pairs that keep the base size (the default and building scenes) unchanged. Flat
// windows as further candidates refined more of the multi-date pairs' failures but farther from the
// curves (009-018: 90.9% refined at 0.307 px RMS against 88.8% at 0.281), and windows below the base
// (15 px) did nothing for the building scene: both left out.
std::vector<LsmOptions> smaller_sizes(const LsmOptions& chosen, const LsmOptions& base) {
  std::vector<LsmOptions> out;
  if (!(chosen.window > base.window)) return out;
  out.push_back(base);
  for (const WindowSize& w : window_size_candidates())
    if (w.window > base.window && w.window < chosen.window && w.quadratic == base.quadratic) {
      LsmOptions l = base;
      l.window = w.window, l.taper = w.taper;
      out.push_back(l);
    }
  return out;
}

void recheck_smaller_sizes(const RefinePixels& px, std::vector<Rec>& recs, const std::vector<Eigen::Matrix2d>& A0,
                           const std::vector<LsmOptions>& sizes, const PairMatchOptions& o, const AffineFundamental* F, double blur,
                           double highpass, PairMatchStats& st) {
  st.recheck_quantile = o.recheck_quantile;
  if (sizes.empty() || !(o.recheck_quantile < 1)) return;
  std::vector<double> sig;
  for (const Rec& r : recs)
    if (r.ok && r.smaller < 0 && !r.retried && !r.at_edge) sig.push_back(r.sigma);
  double thr = INFINITY;  // too few to take a quantile: only the failed records
  if (sig.size() >= 10) {
    const size_t k = std::min(sig.size() - 1, static_cast<size_t>(o.recheck_quantile * static_cast<double>(sig.size())));
    std::nth_element(sig.begin(), sig.begin() + static_cast<long>(k), sig.end());
    thr = sig[k];
    st.recheck_sigma = thr;
  }
  // the records, and the first size each still needs (the base was tried where the chosen size failed)
  std::vector<size_t> idx;
  std::vector<size_t> from;
  for (size_t j = 0; j < recs.size(); ++j) {
    const Rec& r = recs[j];
    if (r.retried || r.at_edge) continue;
    if (r.ok && r.smaller < 0 && r.sigma > thr) idx.push_back(j), from.push_back(0);
    else if ((r.ok && r.smaller == 0) || (!r.ok && failed_on_content(r.status))) idx.push_back(j), from.push_back(1);
  }
  for (size_t s = 0; s < sizes.size(); ++s) {
    std::vector<size_t> at;
    for (size_t i = 0; i < idx.size(); ++i)
      if (from[i] <= s) at.push_back(idx[i]);
    if (at.empty()) continue;
    std::vector<Rec> sub;
    std::vector<Eigen::Matrix2d> subA;
    for (size_t j : at) sub.push_back(recs[j]), subA.push_back(A0[j]);
    refine_records(px, sub, subA, sizes[s], o, F, o.ransac_threshold, blur, highpass, false);
    for (size_t i = 0; i < at.size(); ++i) {
      Rec& r = recs[at[i]];
      if (!sub[i].ok || (r.ok && !(sub[i].sigma < r.sigma))) continue;
      const bool rechecked = r.ok && r.smaller < 0;
      r = sub[i];
      r.smaller = static_cast<int>(s);
      r.rechecked = rechecked || r.rechecked;
    }
  }
}

// 5c. The window's shape model (PairMatchOptions::shape). Automatic: the high-pass estimate's sample is
// refined with the quadratic stages and the curvature's significance measured (lsm_refine.hpp,
// LsmResult::curvature_chi2); where its median over the sample exceeds kQuadraticChi2 the map curves
// within the windows of most of the pair, and every match gets the quadratic model, else the affine.
// One model per pair, not per match: chosen match by match (at any threshold), the Marseille triplet's
// trifocal fit and transfer came out worse than with either model throughout (a match's affine bias is
// shared by a track's pairs only when they use the same model). Medians seen (chi-square with one degree
// of freedom: 0.45): tp-synth relief 150/80/40/15 m 74/16/6.9/1.2; the 66 Jacksonville pairs 0.24 to 2.74
// (median 0.53; only 004-009, 17 degrees apart over buildings, above 2), Marseille and La Reunion 0.3 to
// 0.6. On real pairs the quadratic model mostly adds noise along the epipolar lines, where the heights are:
// with it on every pair the Jacksonville block's ground points against the lidar (slopes under 5
// degrees) had an NMAD of 0.352 m, 0.336 m affine (0.335 m with 004-009 alone quadratic).
constexpr double kQuadraticChi2 = 2;
ShapeChoice choose_pair_shape(const RefinePixels& px, const std::vector<Rec>& recs, const std::vector<Eigen::Matrix2d>& A0,
                              const LsmOptions& lsm, const PairMatchOptions& o, const AffineFundamental* F, double blur, double highpass) {
  ShapeChoice sc;
  if (o.shape != PairMatchOptions::Shape::automatic) {
    sc.quadratic = o.shape == PairMatchOptions::Shape::quadratic;
    return sc;
  }
  if (recs.size() < 50) return sc;  // too few to judge: affine
  const RecordSample sample = sample_records(recs, A0, kHighpassSample);
  LsmOptions q = lsm;
  q.quadratic = true;
  q.measure_curvature = true;
  std::vector<Rec> s = sample.recs;
  refine_records(px, s, sample.A0, q, o, F, o.ransac_threshold, blur, highpass, false, /*per_record=*/true);
  std::vector<double> c;
  for (const Rec& r : s)
    if (std::isfinite(r.curvature_chi2)) c.push_back(r.curvature_chi2);
  if (c.size() < 20) return sc;
  std::nth_element(c.begin(), c.begin() + static_cast<long>(c.size() / 2), c.end());
  sc.median_chi2 = c[c.size() / 2];
  sc.samples = static_cast<long>(c.size());
  sc.quadratic = sc.median_chi2 > kQuadraticChi2;
  return sc;
}

// The sample's refinements at the size chosen and at the base, kept for the refinement of every record
// (refine_pair_records): on a pair of at most kSizeSample matches the choice has refined them all already.
struct SizeSampleRuns {
  std::vector<size_t> idx;  // the sampled records
  std::vector<Rec> chosen, base;
};

// 5d. The window's size (PairMatchOptions::choose_size, window_size.hpp): up to kSizeSample records
// refined at lsm's size and at the larger candidates (affine, then quadratic, at each size), the
// differences compared along and across the verified epipolar geometry's lines. Only where the base
// window is affine: the quadratic one is chosen where the map curves within the base window already, and
// it sizes its own last stage (lsm_refine.hpp, adaptive). Figures (tp-synth truth, triplets' views 2+3
// median / p90 px; real pairs, RMS distance to the RPC epipolar curves with an affine bias per image
// removed, px): relief 15 m 0.0212 / 0.0557 -> 0.0156 / 0.0382 (taper 5 and 7 quadratic); the building
// scene keeps the base (pairs at taper 5 affine: ratios 2.02, 1.34, 1.56, truth 0.066, 0.090, 0.062 px
// against 0.041, 0.048, 0.039); La Reunion 0.230 -> 0.163 (taper 7 quadratic, ratio 0.95); Marseille's
// triplet ML RMSE 0.119 -> 0.097. The Jacksonville block's ground points against the lidar are no
// better for it (flat ground 0.335 -> 0.347 m from the pairwise tracks): the quadratic model's noise
// along the epipolar lines, which the comparison with the noisier base does not show.
WindowSizeChoice choose_pair_size(const RefinePixels& px, const std::vector<Rec>& recs, const std::vector<Eigen::Matrix2d>& A0,
                                  const LsmOptions& lsm, const PairMatchOptions& o, const AffineFundamental* F, double blur,
                                  double highpass, SizeSampleRuns& runs) {
  WindowSizeChoice c;
  c.size = {lsm.taper, lsm.window, lsm.quadratic};
  if (!o.choose_size || lsm.quadratic || !F || lsm.epipolar_dir.isZero() || recs.size() < 50) return c;
  const RecordSample sample = sample_records(recs, A0, kSizeSample);
  std::vector<WindowSize> candidates;
  for (const WindowSize& w : window_size_candidates())
    if (!(w.quadratic && o.shape == PairMatchOptions::Shape::affine)) candidates.push_back(w);  // --shape affine: affine only
  std::vector<std::pair<WindowSize, std::vector<Rec>>> tried;  // the base first
  c = choose_window_size(
      [&](const WindowSize& w) {
        LsmOptions l = lsm;
        l.taper = w.taper, l.window = w.window, l.quadratic = w.quadratic;
        std::vector<Rec> s = sample.recs;
        refine_records(px, s, sample.A0, l, o, F, o.ransac_threshold, blur, highpass, false, /*per_record=*/true);
        tried.emplace_back(w, s);
        WindowSizeSample out;
        out.xy.resize(static_cast<Eigen::Index>(s.size()), 4);
        for (size_t k = 0; k < s.size(); ++k) {
          out.ok.push_back(s[k].ok);
          out.xy.row(static_cast<Eigen::Index>(k)) << s[k].x1, s[k].y1, s[k].x2, s[k].y2;
        }
        return out;
      },
      c.size, candidates, lsm.epipolar_dir);
  c.samples = static_cast<long>(sample.recs.size());
  for (auto& t : tried)
    if (t.first.same_size(c.size) && t.first.quadratic == c.size.quadratic) {
      runs.idx = sample_indices(recs.size(), kSizeSample);
      runs.chosen = std::move(t.second);
      runs.base = tried.front().second;
      break;
    }
  return c;
}

// 5e. Every record refined at the chosen size (lsm), the sampled ones taken from the size's choice; with
// `base` (a larger size chosen), a record that fails on its content there is refined at the base size.
void refine_pair_records(const RefinePixels& px, std::vector<Rec>& recs, const std::vector<Eigen::Matrix2d>& A0, const LsmOptions& lsm,
                         const PairMatchOptions& o, const AffineFundamental* F, double blur, double highpass, const LsmOptions* base,
                         const SizeSampleRuns& runs) {
  if (runs.idx.empty()) {
    refine_records(px, recs, A0, lsm, o, F, o.ransac_threshold, blur, highpass, o.progress, false, 0, base, true);
    return;
  }
  std::vector<char> sampled(recs.size(), 0);
  for (size_t k = 0; k < runs.idx.size(); ++k) {
    Rec r = runs.chosen[k];
    if (r.status == LsmStatus::OutOfImage) continue;  // refined below, its window cut at the edge
    if (base && failed_on_content(r.status) && runs.base[k].ok) r = runs.base[k], r.smaller = 0;
    recs[runs.idx[k]] = r;
    sampled[runs.idx[k]] = 1;
  }
  std::vector<size_t> rest;
  for (size_t j = 0; j < recs.size(); ++j)
    if (!sampled[j]) rest.push_back(j);
  if (rest.empty()) return;
  std::vector<Rec> sub;
  std::vector<Eigen::Matrix2d> subA;
  for (size_t j : rest) sub.push_back(recs[j]), subA.push_back(A0[j]);
  refine_records(px, sub, subA, lsm, o, F, o.ransac_threshold, blur, highpass, o.progress, false, 0, base, true);
  for (size_t i = 0; i < rest.size(); ++i) recs[rest[i]] = sub[i];
}

// 5a. The relative blur of the two images (relative_blur.hpp): o.blur when given, else estimated on up to
// 200 records spread evenly over the list, each candidate a refinement of that sample scored by the
// median final correlation (a failed refinement counts its correlation too, 0 when none), record by
// record on its own window. px: pixels that hold the sample's windows (estimate_pixels, or all held).
RelativeBlur choose_relative_blur(const RefinePixels& px, const std::vector<Rec>& recs,
                                  const std::vector<Eigen::Matrix2d>& A0, const LsmOptions& lsm, const PairMatchOptions& o,
                                  const AffineFundamental* F) {
  RelativeBlur rb;
  if (o.blur) {
    rb.sigma = *o.blur;
    return rb;
  }
  if (recs.size() < 50) return rb;  // too few to judge: none
  const RecordSample sample = sample_records(recs, A0, kBlurSample);
  auto score = [&](double sigma) {
    std::vector<Rec> s = sample.recs;
    refine_records(px, s, sample.A0, lsm, o, F, o.ransac_threshold, sigma, 0, false, /*per_record=*/true);
    std::vector<double> c;
    for (const Rec& r : s) c.push_back(r.corr);
    std::nth_element(c.begin(), c.begin() + static_cast<long>(c.size() / 2), c.end());
    return c[c.size() / 2];
  };
  return estimate_relative_blur(score);
}

// 5b. The local-mean high-pass of both images (radiometric_highpass.hpp): o.highpass when given, else
// chosen on up to 300 records spread evenly over the list (after the relative blur), each candidate a
// refinement of that sample scored by the spread of its refined positions about their own affine
// epipolar geometry. Needs the pair's epipolar geometry (F) and 50 records: otherwise none.
// px: as for choose_relative_blur.
HighpassChoice choose_pair_highpass(const RefinePixels& px, const std::vector<Rec>& recs,
                               const std::vector<Eigen::Matrix2d>& A0, const LsmOptions& lsm, const PairMatchOptions& o,
                               const AffineFundamental* F, double blur) {
  HighpassChoice hc;
  if (o.highpass) {
    hc.sigma = *o.highpass;
    return hc;
  }
  if (!F || recs.size() < 50) return hc;
  const RecordSample sample = sample_records(recs, A0, kHighpassSample);
  hc = choose_highpass([&](double sigma) {
    std::vector<Rec> s = sample.recs;
    refine_records(px, s, sample.A0, lsm, o, F, o.ransac_threshold, blur, sigma, false, /*per_record=*/true);
    std::vector<int> ok;
    for (size_t k = 0; k < s.size(); ++k)
      if (s[k].ok) ok.push_back(static_cast<int>(k));
    Eigen::MatrixX4d xy(static_cast<Eigen::Index>(ok.size()), 4);
    for (size_t q = 0; q < ok.size(); ++q) {
      const Rec& r = s[static_cast<size_t>(ok[q])];
      xy.row(static_cast<Eigen::Index>(q)) << r.x1, r.y1, r.x2, r.y2;
    }
    return epipolar_spread(xy);
  });
  hc.samples = static_cast<long>(sample.recs.size());
  return hc;
}

// 6. The records in order: the refined ones, and those whose refinement was rejected at their keypoint
// position (x2, y2 = kx2, ky2; sigma st.unrefined_sigma; refined 0) unless o.keep_unrefined is false.
Matches assemble_matches(const std::vector<Rec>& recs, const PairMatchOptions& o, PairMatchStats& st) {
  Matches M;
  size_t nout = 0;
  long nref = 0;
  for (const Rec& r : recs) {
    if (r.ok) {
      ++nref, st.retried += r.retried, st.rechecked += r.rechecked, st.at_edge += r.at_edge;
      if (r.smaller >= 0) ++st.at_smaller.at(static_cast<size_t>(r.smaller));
    }
    else if (o.keep_unrefined) st.unrefined[static_cast<int>(r.status)]++;
    else st.dropped[static_cast<int>(r.status)]++;
    if (r.ok || o.keep_unrefined) ++nout;
  }
  st.refined = o.refine ? nref : 0;
  st.unrefined_sigma = std::max(o.unrefined_sigma, st.ransac_rms);
  M.xy.resize(static_cast<Eigen::Index>(nout), 4);
  M.extra.names = {"kx2", "ky2"};
  if (o.refine) M.extra.names.insert(M.extra.names.end(), {"sigma", "corr", "refined"});
  M.extra.values.resize(static_cast<Eigen::Index>(nout), static_cast<Eigen::Index>(M.extra.names.size()));
  Eigen::Index k = 0;
  for (const Rec& r : recs) {
    if (!r.ok && !o.keep_unrefined) continue;
    M.id1.push_back(r.id1);
    M.id2.push_back(r.id2);
    if (r.ok) M.xy.row(k) << r.x1, r.y1, r.x2, r.y2;
    else M.xy.row(k) << r.x1, r.y1, r.kx2, r.ky2;
    M.extra.values(k, 0) = r.kx2;
    M.extra.values(k, 1) = r.ky2;
    if (o.refine) {
      M.extra.values(k, 2) = r.ok ? r.sigma : st.unrefined_sigma;
      M.extra.values(k, 3) = r.corr;
      M.extra.values(k, 4) = r.ok ? 1 : 0;
    }
    ++k;
  }
  return M;
}

// "REASON N, REASON N" of the nonzero counts, by LsmStatus.
std::string counts_by_reason(const long (&count)[kLsmStatusCount]) {
  std::string s;
  for (int k = 1; k < kLsmStatusCount; ++k)
    if (count[k]) s += (s.empty() ? "" : ", ") + std::string(to_string(static_cast<LsmStatus>(k))) + " " + std::to_string(count[k]);
  return s.empty() ? "none" : s;
}

// The header's account of the descriptor search.
std::string search_description(const PairMatchStats& st, const PairMatchOptions& o) {
  std::string search = "global";
  if (st.rpc_guided) {
    auto h = [](double v) { return format_number(std::round(v * 10) / 10); };
    search = "rpc-guided: epipolar curves over " + h(st.rpc.h_lo) + ".." + h(st.rpc.h_hi) + " m";
    if (st.rpc.narrowed)
      search += ", narrowed by the affine F of " + std::to_string(st.rpc.coarse_inliers) + " of " +
                std::to_string(st.rpc.coarse_putative) + " matches of the strongest keypoints to " + h(st.rpc.cell_h_lo) +
                ".." + h(st.rpc.cell_h_hi) + " m, bias across the curves " + h(st.rpc.bias_min) + ".." + h(st.rpc.bias_max) +
                " px (a plane leaves " + format_number(std::round(st.rpc.bias_rms * 100) / 100) + " px rms), band " +
                format_number(std::round(std::max(o.guide.band, 3 * st.rpc.bias_rms) * 100) / 100) + " px";
    else
      search += " (no coarse geometry: " + std::to_string(st.rpc.coarse_inliers) + " inliers)";
    search += ", mean length " + h(st.rpc.mean_length) + " px, margin " + format_number(st.rpc.coarse_margin) +
              " px, ratio region +" + format_number(o.guide.ratio_margin) + " px";
    if (st.rpc.unlocalized > 0) search += ", " + std::to_string(st.rpc.unlocalized) + " keypoints without a curve";
  } else if (st.guided) {
    search = "guided: coarse affine F from " + std::to_string(st.guide.coarse_inliers) + " of " +
             std::to_string(st.guide.coarse_putative) + " matches of the strongest keypoints, band " +
             format_number(o.guide.band) + " px, parallax " + format_number(std::round(st.guide.parallax_min * 10) / 10) +
             ".." + format_number(std::round(st.guide.parallax_max * 10) / 10) + " px + margin " +
             format_number(o.guide.parallax_margin) + ", ratio region +" + format_number(o.guide.ratio_margin) + " px";
    if (st.rpc_fallback)
      search += " (the RPC epipolar curves held no geometry within " + format_number(st.rpc.coarse_margin) + " px: " +
                std::to_string(st.rpc.coarse_inliers) + " of " + std::to_string(st.rpc.coarse_putative) + " coarse matches)";
  } else if (o.guided) {
    search = "global (the guided search found no coarse geometry)";
  }
  return search;
}

// The "# highpass:" header value: what the refinement used and, when chosen here, the spreads it saw.
std::string describe_highpass(const HighpassChoice& h, const PairMatchOptions& o) {
  return describe_highpass_choice(h, "both images", o.highpass.has_value(), "sampled matches", "spread about their epipolar lines",
                                  "(not estimated: fewer than 50 verified matches or no epipolar geometry)");
}

// The "# shape:" header value: the window's model and, when chosen here, what the sample showed.
std::string describe_shape(const ShapeChoice& c, const WindowSize& used, const PairMatchOptions& o) {
  std::string s = c.quadratic ? "quadratic (the map bends along the epipolar lines within the window)" : "affine";
  if (o.shape != PairMatchOptions::Shape::automatic) return s + " (--shape)";
  if (used.quadratic && !c.quadratic) s = "quadratic with the larger window (# size:); at the base window affine";
  if (c.samples == 0) return s + " (not estimated: fewer than 50 verified matches)";
  return s + " (estimated on " + std::to_string(c.samples) + " sampled matches: median significance of the curvature, chi-square, " +
         format_number(std::round(c.median_chi2 * 100) / 100) + ", quadratic above " + format_number(kQuadraticChi2) + ")";
}

// The refinement line's account of the records refined at a smaller size than the pair's.
std::string describe_smaller_sizes(const PairMatchStats& st) {
  long n = 0;
  std::string by;
  for (size_t k = 0; k < st.at_smaller.size(); ++k) {
    if (st.at_smaller[k] == 0) continue;
    n += st.at_smaller[k];
    by += std::string(by.empty() ? "" : ", ") + std::to_string(st.at_smaller[k]) + " at taper " + format_number(st.smaller_sizes[k].taper) +
          " px, window " + std::to_string(st.smaller_sizes[k].window) + " px" + (st.smaller_sizes[k].quadratic ? " quadratic" : " affine");
  }
  if (n == 0) return "";
  if (st.rechecked == 0) return " (" + std::to_string(n) + " at a smaller size, where the pair's failed: " + by + ")";
  return " (" + std::to_string(n) + " at a smaller size: " + by + "; " + std::to_string(st.rechecked) +
         " of them where the pair's size gave a sigma above its " + format_number(st.recheck_quantile * 100) + "th percentile, " +
         format_number(std::round(st.recheck_sigma * 1e4) / 1e4) + " px, the others where it failed)";
}

// The header lines that say how the records were made.
std::string retry_list(const std::vector<int>& w) {
  std::string s;
  for (int v : w) s += (s.empty() ? "" : ", ") + std::to_string(v);
  return s;
}

void describe_run(Matches& M, const ImageSource& a, const ImageSource& b, const PairMatchOptions& o, const PairMatchStats& st,
                  bool lsm_epipolar) {
  meta_set(M.meta, "detector1", detector_tag(o.sift, a));
  meta_set(M.meta, "detector2", detector_tag(o.sift, b));
  meta_set(M.meta, "keypoints", std::to_string(st.keypoints1) + " " + std::to_string(st.keypoints2));
  meta_set(M.meta, "putative", std::to_string(st.putative) + " (ratio " + format_number(o.desc.ratio) +
                                   (o.desc.mutual ? ", mutual" : "") + "; " + search_description(st, o) + ")");
  meta_set(M.meta, "verified", std::to_string(st.verified) + (st.no_parallax ? " (no parallax: 2-D affine map RANSAC" : " (affine F RANSAC") +
                                   ", threshold " + format_number(o.ransac_threshold) +
                                   " px, seed " + std::to_string(o.seed) + ", inlier rms " + format_number(std::round(st.ransac_rms * 1e4) / 1e4) + " px)");
  if (o.grid > 0) meta_set(M.meta, "grid", std::to_string(o.grid) + "x" + std::to_string(o.grid) + ", " + std::to_string(o.per_cell) + " per cell: " + std::to_string(st.gridded));
  if (o.refine) {
    meta_set(M.meta, "refinement", "lsm window " + std::to_string(2 * (st.size.size.window / 2) + 1) + (o.lsm.l1 ? " L1" : " L2") + " taper " + format_number(st.size.size.taper) +
                                       " max_shift " + format_number(o.lsm.max_shift) + " max_sigma " + format_number(o.lsm.max_sigma) +
                                       " min_corr " + format_number(o.lsm.min_corr) +
                                       (o.lsm.mask_k > 0 ? " residual mask " + format_number(o.lsm.mask_k) + " (min_inliers " + format_number(o.lsm.min_inliers) + ")" : "") +
                                       (o.lsm.mask_fit_k > 0 ? " fit mask " + format_number(o.lsm.mask_fit_k) : "") +
                                       " sigma " + format_number(o.lsm.sigma_scale * (st.size.size.quadratic ? o.lsm.quadratic_sigma_ratio : 1.0)) + " x fit (+) " + format_number(o.lsm.sigma_floor) + " px" +
                                       (st.size.size.quadratic ? std::string(" quadratic") + (lsm_epipolar ? " (along the epipolar lines)" : "") : "") +
                                       ": " + std::to_string(st.refined) + " converged" +
                                       describe_smaller_sizes(st) +
                                       (st.retried > 0 ? " (" + std::to_string(st.retried) + " at a retry window: " + retry_list(o.retry_windows) + " px)" : "") +
                                       (st.at_edge > 0 ? " (" + std::to_string(st.at_edge) + " at an image's edge, the window cut to its pixels inside: edge share " +
                                                             format_number(o.edge_share) + ")"
                                                       : ""));
    long nu = 0, nd = 0;
    for (int k = 0; k < kLsmStatusCount; ++k) nu += st.unrefined[k], nd += st.dropped[k];
    meta_set(M.meta, "unrefined", std::to_string(nu) + " kept at the keypoint position, refined 0, sigma " +
                                      format_number(std::round(st.unrefined_sigma * 1e4) / 1e4) + " px (" + counts_by_reason(st.unrefined) + ")");
    meta_set(M.meta, "dropped", std::to_string(nd) + " (" + counts_by_reason(st.dropped) + ")");
    const RelativeBlur& rb = st.blur;
    const std::string which = rb.sigma > 0 ? "image 1" : "image 2";
    std::string blur = rb.sigma == 0 ? std::string("none") : which + " blurred by a Gaussian of " + format_number(std::abs(rb.sigma)) + " px before refinement";
    if (rb.evaluations > 0)
      blur += " (estimated: median correlation of the sampled matches " + format_number(std::round(rb.score * 1e4) / 1e4) +
              (rb.sigma == 0 ? "" : ", " + format_number(std::round(rb.score_none * 1e4) / 1e4) + " unblurred") + ")";
    else if (o.blur)
      blur += " (--blur)";
    meta_set(M.meta, "blur", blur);
    meta_set(M.meta, "highpass", describe_highpass(st.highpass, o));
    meta_set(M.meta, "shape", describe_shape(st.shape, st.size.size, o));
    meta_set(M.meta, "size", describe_window_size(st.size, !o.choose_size,
                                                  st.shape.quadratic ? "(the quadratic model: its last stage sizes its own taper)"
                                                                     : "(not estimated: fewer than 50 verified matches or no epipolar geometry)"));
  } else
    meta_set(M.meta, "refinement", "none (raw SIFT positions)");
  meta_set(M.meta, "positions", o.refine ? "x1 y1 keypoint of image1 (fixed template); x2 y2 refined in image2 (refined 1) or its keypoint (refined 0); kx2 ky2 keypoint of image2"
                                         : "x1 y1 keypoint of image1; x2 y2 = kx2 ky2 keypoint of image2");
}

}  // namespace

Matches match_keypoints(const ImageSource& a, const ImageSource& b, Keypoints K1, Keypoints K2, const PairMatchOptions& o,
                        PairMatchStats* stats) {
  // The detection's pyramids, kept for reuse, are not needed from here on, unless detection goes on beside
  // this pair (match_every_pair: live_threads set), whose next image reuses them.
  if (!o.live_threads) release_large_blocks();
  PairMatchStats st;
  st.size.size = {o.lsm.taper, o.lsm.window, o.lsm.quadratic};
  auto clock = std::chrono::steady_clock::now();
  auto lap = [&clock](double& out) {
    auto now = std::chrono::steady_clock::now();
    out = std::chrono::duration<double>(now - clock).count();
    clock = now;
  };
  st.keypoints1 = static_cast<long>(K1.kp.size());
  st.keypoints2 = static_cast<long>(K2.kp.size());

  AffineFundamentalRansac cr;  // the coarse stages' RANSAC
  cr.threshold = o.ransac_threshold;
  cr.max_iterations = o.ransac_iterations;
  cr.seed = o.seed;
  const std::vector<DescriptorMatch> put = putative_matches(a, K1, K2, o, cr, st);
  K1.desc.release();
  K2.desc.release();
  if (!o.live_threads) release_large_blocks();  // the descriptors' blocks went back to the pool: refinement has no use for them
  lap(st.seconds[1]);

  AffineFundamentalResult rr;
  std::vector<size_t> ver = verify_matches(put, K1, K2, o, rr, st);
  thin_to_grid(ver, put, K1, a, o);
  st.gridded = static_cast<long>(ver.size());
  if (o.window) keep_in_window(ver, put, K1, *o.window);
  st.in_window = static_cast<long>(ver.size());
  lap(st.seconds[2]);

  std::vector<Rec> recs(ver.size());
  for (size_t j = 0; j < ver.size(); ++j) {
    const auto& m = put[ver[j]];
    const auto &k1 = K1.kp[m.i1], &k2 = K2.kp[m.i2];
    recs[j] = {K1.id[m.i1], K2.id[m.i2], k1.pt.x, k1.pt.y, k2.pt.x, k2.pt.y, k2.pt.x, k2.pt.y, 0, 0, true, LsmStatus::Ok};
  }
  const bool lsm_epipolar = o.lsm.epipolar_curvature && rr.ok;  // the quadratic stage bends along F's epipolar lines
  if (o.refine && !recs.empty()) {
    std::vector<Eigen::Matrix2d> A0(recs.size());
    for (size_t j = 0; j < recs.size(); ++j) {
      const auto& m = put[ver[j]];
      A0[j] = keypoint_affine(K1.kp[m.i1].size, K1.kp[m.i1].angle, K2.kp[m.i2].size, K2.kp[m.i2].angle);
    }
    LsmOptions lsm = o.lsm;
    // epipolar lines of image 2 run along (-b, a): the direction in which the map bends with the terrain
    if (lsm_epipolar) lsm.epipolar_dir = Eigen::Vector2d(-rr.F.n(1), rr.F.n(0));
    // the refined position is held to the pair model that verified the keypoints (not with a 2-D map: that
    // one holds only for views without parallax, which the LSM may still refine within max_shift)
    const bool with_f = rr.ok && !st.no_parallax;
    const AffineFundamental* F = with_f ? &rr.F : nullptr;
    // the parts of the images the records reach (with the widest filter supports the estimates try)
    std::vector<size_t> all(recs.size());
    std::iota(all.begin(), all.end(), size_t(0));
    const RefineGroup reach = refine_group(std::move(all), recs, A0, o, kWidestFilterSupport, kWidestFilterSupport);
    const RefinePixels px(a, b, {reach.a, reach.b}, o.refine_hold_pixels);
    const std::optional<RefinePixels> windows = estimate_pixels(px, recs, A0, o);
    const RefinePixels& epx = windows ? *windows : px;
    // The blur, high-pass and shape estimates refine their samples without the fit's mask (lsm.mask_fit_k),
    // as their thresholds were set: the blur and the high-pass measure how the two images' radiometry
    // differs over whole windows, which a fit that leaves its worst pixels out hides (with the mask they
    // chose a blur and no high-pass on Jacksonville pairs 003-006 and 004-007, whose distance to the RPC
    // epipolar curves then grew from 0.247 and 0.275 to 0.313 and 0.368 px RMS), and the curvature's
    // significance moves with the mask too (Jacksonville 001-004 1.27 -> 1.09). The size's choice and the
    // refinement itself use it.
    LsmOptions unmasked = lsm;
    unmasked.mask_fit_k = 0;
    st.blur = choose_relative_blur(epx, recs, A0, unmasked, o, F);
    st.highpass = choose_pair_highpass(epx, recs, A0, unmasked, o, F, st.blur.sigma);
    st.shape = choose_pair_shape(epx, recs, A0, unmasked, o, F, st.blur.sigma, st.highpass.sigma);
    lsm.quadratic = st.shape.quadratic;
    SizeSampleRuns runs;
    st.size = choose_pair_size(epx, recs, A0, lsm, o, F, st.blur.sigma, st.highpass.sigma, runs);
    const LsmOptions base = lsm;
    lsm.taper = st.size.size.taper, lsm.window = st.size.size.window;
    const bool larger = lsm.window != base.window || lsm.taper != base.taper;
    lsm.quadratic = st.size.size.quadratic;
    refine_pair_records(px, recs, A0, lsm, o, F, st.blur.sigma, st.highpass.sigma, larger ? &base : nullptr, runs);
    const std::vector<LsmOptions> smaller = smaller_sizes(lsm, base);
    for (const LsmOptions& l : smaller) st.smaller_sizes.push_back({l.taper, l.window, l.quadratic});
    st.at_smaller.assign(smaller.size(), 0);
    recheck_smaller_sizes(px, recs, A0, smaller, o, F, st.blur.sigma, st.highpass.sigma, st);
    retry_failed_records(px, recs, A0, lsm, o, F, st.blur.sigma, st.highpass.sigma);
  }
  lap(st.seconds[3]);

  Matches M = assemble_matches(recs, o, st);
  M.image1 = {a.path, a.info.width, a.info.height};
  M.image2 = {b.path, b.info.width, b.info.height};
  describe_run(M, a, b, o, st, lsm_epipolar);
  if (stats) *stats = st;
  return M;
}

std::string no_match_reason(const PairMatchStats& st, const PairMatchOptions& o) {
  if (st.rpc_guided && st.keypoints1 > 0 && st.rpc.unlocalized >= st.keypoints1)
    return "the RPC model of image 1 gives no epipolar curve for any of its " + std::to_string(st.keypoints1) +
           " keypoints: is it the model of this image?";
  if (st.rpc_guided && !st.rpc.narrowed) {
    const std::string heights = format_number(st.rpc.h_lo) + ".." + format_number(st.rpc.h_hi) + " m";
    return "the RPC epipolar curves over the heights " + heights +
           (o.rpc_guide.height_given ? " (--height-range)" : " (the models' range)") + " held no geometry within " +
           format_number(st.rpc.coarse_margin) + " px: " + std::to_string(st.rpc.coarse_inliers) + " of " +
           std::to_string(st.rpc.coarse_putative) + " coarse matches" +
           (o.rpc_only ? "" : ", and the images' own coarse stage found none either") +
           "; the models (a bias beyond --rpc-max-margin), the height range or the overlap may be at fault";
  }
  return "do the images overlap?";
}

std::string rpc_fallback_reason(const PairMatchStats& st, const PairMatchOptions& o) {
  const std::string heights = format_number(st.rpc.h_lo) + ".." + format_number(st.rpc.h_hi) + " m";
  return "over the heights " + heights + (o.rpc_guide.height_given ? " (--height-range)" : " (the models' range)") +
         " held no geometry within " + format_number(st.rpc.coarse_margin) + " px (--rpc-max-margin)"
         "; the images' own coarse stage found one: " +
         (o.rpc_guide.height_given ? "the height range misses the terrain, or the models disagree with the images by more than the margin"
                                   : "the models disagree with the images by more than that") +
         " (rpc-adjust corrects models)";
}

}  // namespace tpkit
