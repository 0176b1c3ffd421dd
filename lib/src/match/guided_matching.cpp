#include "tpkit/match/guided_matching.hpp"

#include "tpkit/core/cpu_dispatch.hpp"
#include "tpkit/core/parallel_for.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <stdexcept>

#if TPKIT_HAS_AVX2
#include <immintrin.h>
#endif

namespace tpkit {

namespace {

cv::Mat rows_of(const cv::Mat& m, const std::vector<int>& idx) {
  cv::Mat out(static_cast<int>(idx.size()), m.cols, m.type());
  for (size_t k = 0; k < idx.size(); ++k) m.row(idx[k]).copyTo(out.row(static_cast<int>(k)));
  return out;
}

// Squared L2 distance of two 128-byte descriptors (whole: a loop the compiler vectorizes, cheaper than
// the branches of an early exit); the baseline of compare_avx2 below.
inline int dist2_u8(const uint8_t* a, const uint8_t* b) {
  int s = 0;
  for (int k = 0; k < 128; ++k) {
    const int d = static_cast<int>(a[k]) - static_cast<int>(b[k]);
    s += d * d;
  }
  return s;
}

// Image-2 keypoints bucketed by (d, s) = (n . x2, u . x2) of one frame (u unit, n = (u.y, -u.x)):
// counting sort into a regular grid of bd x bs pixels.
struct Buckets {
  Eigen::Vector2d n{0, -1}, u{1, 0};
  double d0 = 0, s0 = 0, bd = 8, bs = 32;
  int nd = 1, ns = 1;
  std::vector<int> start, items;
  void build(const std::vector<cv::KeyPoint>& kp) {
    const size_t count = kp.size();
    std::vector<double> d(count), s(count);
    double d1 = -1e300, s1 = -1e300;
    d0 = s0 = 1e300;
    for (size_t j = 0; j < count; ++j) {
      d[j] = n.x() * kp[j].pt.x + n.y() * kp[j].pt.y;
      s[j] = u.x() * kp[j].pt.x + u.y() * kp[j].pt.y;
      d0 = std::min(d0, d[j]), d1 = std::max(d1, d[j]);
      s0 = std::min(s0, s[j]), s1 = std::max(s1, s[j]);
    }
    nd = std::max(1, static_cast<int>(std::min(1e6, (d1 - d0) / bd)) + 1);
    ns = std::max(1, static_cast<int>(std::min(1e6, (s1 - s0) / bs)) + 1);
    while (static_cast<double>(nd) * ns > 4.0 * static_cast<double>(count) + 1024) {  // sparse keypoints, long extent
      bd *= 2, bs *= 2;
      nd = std::max(1, static_cast<int>((d1 - d0) / bd) + 1);
      ns = std::max(1, static_cast<int>((s1 - s0) / bs) + 1);
    }
    start.assign(static_cast<size_t>(nd) * ns + 1, 0);
    for (size_t j = 0; j < count; ++j) ++start[cell(d[j], s[j]) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    items.resize(count);
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (size_t j = 0; j < count; ++j) items[fill[cell(d[j], s[j])]++] = static_cast<int>(j);  // ascending j per cell
  }
  int d_index(double dv) const { return std::clamp(static_cast<int>(std::floor((dv - d0) / bd)), 0, nd - 1); }
  int s_index(double sv) const { return std::clamp(static_cast<int>(std::floor((sv - s0) / bs)), 0, ns - 1); }
  size_t cell(double dv, double sv) const { return static_cast<size_t>(d_index(dv)) * ns + s_index(sv); }
};

struct Best {
  int dist = std::numeric_limits<int>::max();
  int idx = -1;
};

// What one distance d2 between image-1 keypoint i and image-2 keypoint j changes (inner: j lies in i's
// region): acc the nearest in the region, m1 and m2 the two nearest in the wider one, r = bk[j] the
// nearest image-1 keypoint of j so far (the mutual check); ties to the lower index.
[[gnu::always_inline]] inline void consider(int d2, int j, bool inner, int i, Best& r, Best& acc, Best& m1, Best& m2) {
  // a pair farther than both i's second best and j's best so far changes nothing
  if (d2 > m2.dist && d2 > r.dist) return;
  if (d2 < m1.dist || (d2 == m1.dist && j < m1.idx)) {
    m2 = m1;
    m1 = {d2, j};
  } else if (d2 < m2.dist || (d2 == m2.dist && j < m2.idx)) {
    m2 = {d2, j};
  }
  if (inner && (d2 < acc.dist || (d2 == acc.dist && j < acc.idx))) acc = {d2, j};
  if (d2 < r.dist || (d2 == r.dist && i < r.idx)) r = {d2, i};
}

// The rows of desc2 are scattered over the matrix: ask for the row of the candidate a few ahead.
[[gnu::always_inline]] inline void ask_ahead(const int* cand, int c, int nc, const int* items, const cv::Mat& desc2) {
  if (c + 4 < nc) {
    const uint8_t* ahead = desc2.ptr<uint8_t>(items[cand[c + 4] >> 1]);
    __builtin_prefetch(ahead);
    __builtin_prefetch(ahead + 64);
  }
}

// Descriptor q (image-1 keypoint i) against the candidates cand[0..nc) of one bucket row (bucket
// position * 2 + 1 if in the region; items: bucket position -> image-2 keypoint).
void compare(const int* cand, int nc, const int* items, const cv::Mat& desc2, const uint8_t* q, int i, std::vector<Best>& bk,
              Best& acc, Best& m1, Best& m2) {
  for (int c = 0; c < nc; ++c) {
    ask_ahead(cand, c, nc, items, desc2);
    const int j = items[cand[c] >> 1];
    consider(dist2_u8(q, desc2.ptr<uint8_t>(j)), j, cand[c] & 1, i, bk[static_cast<size_t>(j)], acc, m1, m2);
  }
}

#if TPKIT_HAS_AVX2
// The same with AVX2 intrinsics, q widened to 16 bits once for all candidates (the vectorised loop of
// dist2_u8 widens both descriptors for each one): per 16 components, widen the candidate's, subtract,
// square and add pairs (vpmaddwd: |d| <= 255, so d^2 + d'^2 fits), add. The same integer distances.
TPKIT_AVX2 void compare_avx2(const int* cand, int nc, const int* items, const cv::Mat& desc2, const uint8_t* q, int i,
                             std::vector<Best>& bk, Best& acc, Best& m1, Best& m2) {
  __m256i qw[8];
  for (int k = 0; k < 8; ++k) qw[k] = _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(q + 16 * k)));
  for (int c = 0; c < nc; ++c) {
    ask_ahead(cand, c, nc, items, desc2);
    const int j = items[cand[c] >> 1];
    const uint8_t* p = desc2.ptr<uint8_t>(j);
    __m256i s0 = _mm256_setzero_si256(), s1 = _mm256_setzero_si256();
    for (int k = 0; k < 8; k += 2) {
      const __m256i d0 = _mm256_sub_epi16(qw[k], _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16 * k))));
      const __m256i d1 = _mm256_sub_epi16(qw[k + 1], _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16 * k + 16))));
      s0 = _mm256_add_epi32(s0, _mm256_madd_epi16(d0, d0));
      s1 = _mm256_add_epi32(s1, _mm256_madd_epi16(d1, d1));
    }
    const __m256i s = _mm256_add_epi32(s0, s1);
    __m128i h = _mm_add_epi32(_mm256_castsi256_si128(s), _mm256_extracti128_si256(s, 1));
    h = _mm_add_epi32(h, _mm_shuffle_epi32(h, 0x4E));
    h = _mm_add_epi32(h, _mm_shuffle_epi32(h, 0xB1));
    consider(_mm_cvtsi128_si32(h), j, cand[c] & 1, i, bk[static_cast<size_t>(j)], acc, m1, m2);
  }
}
#endif

// Compares descriptor q (image-1 keypoint i) with the image-2 keypoints in region R and in the region
// `ratio_margin` wider (bx, by: their positions in bucket order): acc the nearest in R, m1 and m2 the two
// nearest in the wider one; bk[j] the nearest image-1 keypoint of j so far (the mutual check).
TPKIT_HOT void search_region(const Buckets& B, const double* bx, const double* by, const SearchRegion& R, const uint8_t* q,
                             const cv::Mat& desc2, double ratio_margin, int i, std::vector<Best>& bk, std::vector<int>& cand,
                             long long& cmp, Best& acc, Best& m1, Best& m2) {
  const Eigen::Vector2d nr(R.u.y(), -R.u.x());
  const double rd = R.band + ratio_margin, ws_lo = -ratio_margin, ws_hi = R.length + ratio_margin;
  // the wider rectangle's corners in the buckets' frame -> the buckets to visit
  double dlo = 1e300, dhi = -1e300, slo = 1e300, shi = -1e300;
  for (double sa : {ws_lo, ws_hi})
    for (double da : {-rd, rd}) {
      const Eigen::Vector2d c = R.a + sa * R.u + da * nr;
      const double dv = B.n.dot(c), sv = B.u.dot(c);
      dlo = std::min(dlo, dv), dhi = std::max(dhi, dv), slo = std::min(slo, sv), shi = std::max(shi, sv);
    }
  const int da = B.d_index(dlo), db = B.d_index(dhi), sa = B.s_index(slo), sb = B.s_index(shi);
  const double ax = R.a.x(), ay = R.a.y(), nx = nr.x(), ny = nr.y(), ux = R.u.x(), uy = R.u.y(), band = R.band, len = R.length;
  for (int a = da; a <= db; ++a) {
    // the buckets of one row are contiguous in bucket order
    const int t0 = B.start[static_cast<size_t>(a) * B.ns + sa], t1 = B.start[static_cast<size_t>(a) * B.ns + sb + 1];
    // which keypoints of the row lie in the wider region (bit 1) and in the region (bit 0): one loop the
    // compiler vectorises, then the compaction (a store per keypoint, no branch: inside is hard to predict)
    const int span = t1 - t0;
    cand.resize(2 * static_cast<size_t>(span));
    int* flag = cand.data() + span;
    const double *px = bx + t0, *py = by + t0;
    for (int k = 0; k < span; ++k) {
      const double vx = px[k] - ax, vy = py[k] - ay;
      const double dd = nx * vx + ny * vy, ss = ux * vx + uy * vy;
      const int wide = static_cast<int>(std::abs(dd) <= rd) & static_cast<int>(ss >= ws_lo) & static_cast<int>(ss <= ws_hi);
      const int inner = static_cast<int>(std::abs(dd) <= band) & static_cast<int>(ss >= 0) & static_cast<int>(ss <= len);
      flag[k] = 2 * wide + inner;
    }
    int nc = 0;
    for (int k = 0; k < span; ++k) {
      cand[static_cast<size_t>(nc)] = 2 * (t0 + k) + (flag[k] & 1);
      nc += flag[k] >> 1;
    }
    cmp += nc;
#if TPKIT_HAS_AVX2
    if (cpu_has_avx2()) {
      compare_avx2(cand.data(), nc, B.items.data(), desc2, q, i, bk, acc, m1, m2);
      continue;
    }
#endif
    compare(cand.data(), nc, B.items.data(), desc2, q, i, bk, acc, m1, m2);
  }
}

}  // namespace

std::vector<int> strongest_spread(const std::vector<cv::KeyPoint>& kp, int total, int grid) {
  std::vector<int> out;
  if (kp.empty()) return out;
  float x0 = kp[0].pt.x, x1 = x0, y0 = kp[0].pt.y, y1 = y0;
  for (const auto& k : kp) {
    x0 = std::min(x0, k.pt.x), x1 = std::max(x1, k.pt.x);
    y0 = std::min(y0, k.pt.y), y1 = std::max(y1, k.pt.y);
  }
  const int cells = grid * grid;
  std::vector<std::vector<int>> by_cell(cells);
  for (int i = 0; i < static_cast<int>(kp.size()); ++i) {
    int cx = std::min(grid - 1, static_cast<int>((kp[i].pt.x - x0) / std::max(1e-3f, x1 - x0) * grid));
    int cy = std::min(grid - 1, static_cast<int>((kp[i].pt.y - y0) / std::max(1e-3f, y1 - y0) * grid));
    by_cell[cy * grid + cx].push_back(i);
  }
  const size_t quota = static_cast<size_t>(std::max(1, total / cells));
  for (auto& c : by_cell) {
    std::stable_sort(c.begin(), c.end(), [&](int a, int b) { return kp[a].response > kp[b].response; });
    if (c.size() > quota) c.resize(quota);
    out.insert(out.end(), c.begin(), c.end());
  }
  std::sort(out.begin(), out.end());
  return out;
}

size_t CellRanges::cell(double x, double y) const {
  const int cx = std::clamp(static_cast<int>((x + 0.5) * grid / std::max(1L, w)), 0, grid - 1);
  const int cy = std::clamp(static_cast<int>((y + 0.5) * grid / std::max(1L, h)), 0, grid - 1);
  return static_cast<size_t>(cy) * grid + cx;
}

CellRanges cell_ranges(const std::vector<Eigen::Vector3d>& xyv, long w, long h, int grid, int min_samples, double margin) {
  CellRanges r;
  r.grid = std::max(1, grid), r.w = w, r.h = h;
  const int G = r.grid;
  double all_lo = 1e300, all_hi = -1e300;
  std::vector<std::vector<double>> per_cell(static_cast<size_t>(G) * G);
  for (const Eigen::Vector3d& s : xyv) {
    per_cell[r.cell(s.x(), s.y())].push_back(s.z());
    all_lo = std::min(all_lo, s.z()), all_hi = std::max(all_hi, s.z());
  }
  r.lo.resize(per_cell.size());
  r.hi.resize(per_cell.size());
  for (int cy = 0; cy < G; ++cy)
    for (int cx = 0; cx < G; ++cx) {
      double a = 1e300, b = -1e300;
      long cnt = 0;
      for (int yy = std::max(0, cy - 1); yy <= std::min(G - 1, cy + 1); ++yy)
        for (int xx = std::max(0, cx - 1); xx <= std::min(G - 1, cx + 1); ++xx)
          for (double p : per_cell[static_cast<size_t>(yy) * G + xx]) {
            a = std::min(a, p), b = std::max(b, p);
            ++cnt;
          }
      if (cnt < min_samples) a = all_lo, b = all_hi;
      r.lo[static_cast<size_t>(cy) * G + cx] = a - margin;
      r.hi[static_cast<size_t>(cy) * G + cx] = b + margin;
    }
  return r;
}

GuidedMatchResult guided_match(const Keypoints& K1, const Keypoints& K2, long w1, long h1,
                               const DescriptorMatchOptions& desc, const GuidedMatchOptions& g,
                               const AffineFundamentalRansac& ransac, int min_inliers, int threads) {
  GuidedMatchResult res;
  if (K1.kp.empty() || K2.kp.empty()) return res;
  // 1. coarse epipolar geometry from the strongest keypoints
  const std::vector<int> c1 = strongest_spread(K1.kp, g.coarse_keypoints, g.coarse_grid);
  const std::vector<int> c2 = strongest_spread(K2.kp, g.coarse_keypoints, g.coarse_grid);
  DescriptorMatchOptions cd = desc;
  cd.exact_below = std::numeric_limits<long>::max();
  const std::vector<DescriptorMatch> coarse = match_descriptors(rows_of(K1.desc, c1), rows_of(K2.desc, c2), cd);
  res.coarse_putative = static_cast<long>(coarse.size());
  if (static_cast<int>(coarse.size()) < std::max(min_inliers, AffineFundamental::MINIMUM_SAMPLES)) return res;
  Eigen::MatrixX4d xy(coarse.size(), 4);
  for (size_t k = 0; k < coarse.size(); ++k) {
    const auto &p = K1.kp[c1[coarse[k].i1]].pt, &q = K2.kp[c2[coarse[k].i2]].pt;
    xy.row(static_cast<Eigen::Index>(k)) << p.x, p.y, q.x, q.y;
  }
  const AffineFundamentalResult rr = ransac_affine_fundamental(xy, ransac);
  res.coarse_inliers = rr.ok ? rr.inliers : 0;
  if (!rr.ok || rr.inliers < min_inliers) return res;
  res.F = rr.F;
  const double nab = std::hypot(rr.F.n(0), rr.F.n(1));
  if (!(nab > 0.05)) return res;  // epipolar lines of image 2 undefined: not two overlapping views
  const Eigen::Vector2d n2(rr.F.n(0) / nab, rr.F.n(1) / nab), u2(-n2.y(), n2.x());
  // epipolar line of x1 in image 2: n2 . x2 = dline(x1)
  const double lc = -rr.F.n(2) / nab, ld = -rr.F.n(3) / nab, le = -rr.F.e / nab;

  // parallax: s2 = u2 . x2 against a plane in x1, over the coarse inliers
  std::vector<Eigen::Index> in;
  for (Eigen::Index k = 0; k < xy.rows(); ++k)
    if (rr.inlier[k]) in.push_back(k);
  Eigen::MatrixX3d A(in.size(), 3);
  Eigen::VectorXd sv(in.size());
  for (size_t q = 0; q < in.size(); ++q) {
    A.row(static_cast<Eigen::Index>(q)) << xy(in[q], 0), xy(in[q], 1), 1.0;
    sv(static_cast<Eigen::Index>(q)) = u2.x() * xy(in[q], 2) + u2.y() * xy(in[q], 3);
  }
  const Eigen::Vector3d plane = A.colPivHouseholderQr().solve(sv);
  const Eigen::VectorXd par = sv - A * plane;
  res.parallax_min = par.minCoeff();
  res.parallax_max = par.maxCoeff();

  // per-cell parallax ranges over image 1
  std::vector<Eigen::Vector3d> samples(in.size());
  for (size_t q = 0; q < in.size(); ++q) samples[q] << xy(in[q], 0), xy(in[q], 1), par(static_cast<Eigen::Index>(q));
  const CellRanges ranges = cell_ranges(samples, w1, h1, g.coarse_grid, g.min_cell_samples, g.parallax_margin);

  // 2. guided search: the band around the epipolar line, over the cell's parallax range
  std::vector<SearchRegion> regions(K1.kp.size());
  for (size_t i = 0; i < K1.kp.size(); ++i) {
    const cv::Point2f p = K1.kp[i].pt;
    const size_t c = ranges.cell(p.x, p.y);
    const double dp = lc * p.x + ld * p.y + le;  // n2 . x2 on the line
    const double sp = plane(0) * p.x + plane(1) * p.y + plane(2);
    regions[i].u = u2;
    regions[i].a = dp * n2 + (sp + ranges.lo[c]) * u2;
    regions[i].length = ranges.hi[c] - ranges.lo[c];
    regions[i].band = g.band;
  }
  RegionMatchResult rm = match_in_regions(K1, K2, regions, desc, g.ratio_margin, threads);
  res.matches = std::move(rm.matches);
  res.candidates_per_query = rm.candidates_per_query;
  res.ok = true;
  return res;
}

RegionMatchResult match_in_regions(const Keypoints& K1, const Keypoints& K2, const std::vector<SearchRegion>& regions,
                                   const DescriptorMatchOptions& desc, double ratio_margin, int threads) {
  RegionMatchResult res;
  const int n1 = static_cast<int>(K1.kp.size()), n2k = static_cast<int>(K2.kp.size());
  if (n1 == 0 || n2k == 0) return res;
  if (regions.size() != K1.kp.size()) throw std::invalid_argument("match_in_regions: one region per image-1 keypoint");
  // the buckets' frame: the regions' mean direction (the epipolar direction varies slowly over a scene)
  Buckets B;
  {
    Eigen::Vector2d sum(0, 0), ref(0, 0);
    std::vector<double> widths;
    for (const SearchRegion& r : regions) {
      if (r.length < 0) continue;
      if (ref.squaredNorm() == 0) ref = r.u;
      sum += r.u.dot(ref) >= 0 ? r.u : Eigen::Vector2d(-r.u);
      widths.push_back(r.band + ratio_margin);
    }
    if (widths.empty()) return res;
    B.u = sum.norm() > 0 ? Eigen::Vector2d(sum.normalized()) : Eigen::Vector2d(1, 0);
    B.n = Eigen::Vector2d(B.u.y(), -B.u.x());
    std::nth_element(widths.begin(), widths.begin() + static_cast<std::ptrdiff_t>(widths.size() / 2), widths.end());
    B.bd = std::max(4.0, widths[widths.size() / 2]);
  }
  B.build(K2.kp);
  // image-2 positions in bucket order, so that a bucket's keypoints are read from contiguous memory
  std::vector<double> bx(static_cast<size_t>(n2k)), by(static_cast<size_t>(n2k));
  for (size_t t = 0; t < B.items.size(); ++t) {
    const cv::Point2f p = K2.kp[static_cast<size_t>(B.items[t])].pt;
    bx[t] = p.x, by[t] = p.y;
  }
  const float ratio2 = static_cast<float>(desc.ratio * desc.ratio);
  std::vector<DescriptorMatch> fwd(static_cast<size_t>(n1), DescriptorMatch{-1, -1, 0.f, 0.f});
  const int W = std::max(1, std::min(threads, 64));
  std::vector<std::vector<Best>> back(static_cast<size_t>(W), std::vector<Best>(static_cast<size_t>(n2k)));
  std::vector<long long> compared(static_cast<size_t>(W), 0);
  const int chunk = 256;
  std::atomic<int> next{0};
  auto work = [&](int w) {
    std::vector<Best>& bk = back[static_cast<size_t>(w)];
    std::vector<int> cand;  // a bucket row's keypoints in the wider region: bucket position * 2 + (1 if in the region)
    long long cmp = 0;
    for (;;) {
      const int b0 = next.fetch_add(chunk);
      if (b0 >= n1) break;
      for (int i = b0; i < std::min(n1, b0 + chunk); ++i) {
        const SearchRegion& R = regions[static_cast<size_t>(i)];
        if (!(R.length >= 0)) continue;
        Best acc, m1, m2;  // best in the region; two best in the wider region
        search_region(B, bx.data(), by.data(), R, K1.desc.ptr<uint8_t>(i), K2.desc, ratio_margin, i, bk, cand, cmp, acc, m1, m2);
        if (acc.idx < 0) continue;
        const Best second = m1.idx == acc.idx ? m2 : m1;
        float ratio = 0.f;
        if (second.idx >= 0) {
          if (!(static_cast<float>(acc.dist) < ratio2 * static_cast<float>(second.dist))) continue;
          ratio = second.dist > 0 ? std::sqrt(static_cast<float>(acc.dist) / static_cast<float>(second.dist)) : 1.f;
        }
        fwd[static_cast<size_t>(i)] = {i, acc.idx, std::sqrt(static_cast<float>(acc.dist)), ratio};
      }
    }
    compared[static_cast<size_t>(w)] = cmp;
  };
  parallel_for(static_cast<size_t>(W), W, [&](size_t w) { work(static_cast<int>(w)); });

  std::vector<Best> bj = std::move(back[0]);
  for (int w = 1; w < W; ++w)
    for (int j = 0; j < n2k; ++j) {
      const Best& o = back[static_cast<size_t>(w)][static_cast<size_t>(j)];
      Best& r = bj[static_cast<size_t>(j)];
      if (o.dist < r.dist || (o.dist == r.dist && o.idx >= 0 && (r.idx < 0 || o.idx < r.idx))) r = o;
    }
  back = {};  // merged into bj
  long long total = 0;
  for (long long c : compared) total += c;
  res.candidates_per_query = static_cast<double>(total) / n1;
  // counted first, then written into a list of their own size: grown by doubling, the list of a 10000²
  // pair's 1.14 million matches and its copies made the peak of the whole run
  auto kept = [&](const DescriptorMatch& m) { return m.i1 >= 0 && (!desc.mutual || bj[static_cast<size_t>(m.i2)].idx == m.i1); };
  res.matches.reserve(static_cast<size_t>(std::count_if(fwd.begin(), fwd.end(), kept)));
  for (const DescriptorMatch& m : fwd)
    if (kept(m)) res.matches.push_back(m);
  return res;
}

}  // namespace tpkit
