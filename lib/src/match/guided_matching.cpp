#include "tpkit/guided_matching.hpp"

#include "tpkit/parallel_for.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

namespace tpkit {

namespace {

// Indices of the strongest keypoints, at most quota per cell of a grid x grid split of their extent.
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

cv::Mat rows_of(const cv::Mat& m, const std::vector<int>& idx) {
  cv::Mat out(static_cast<int>(idx.size()), m.cols, m.type());
  for (size_t k = 0; k < idx.size(); ++k) m.row(idx[k]).copyTo(out.row(static_cast<int>(k)));
  return out;
}

// Squared L2 distance of two 128-byte descriptors, or some value > bound as soon as the partial sum
// over whole 32-byte blocks exceeds `bound` (the rest cannot bring it back).
inline int dist2_u8(const uint8_t* a, const uint8_t* b, int bound) {
  int s = 0;
  for (int blk = 0; blk < 128; blk += 32) {
    for (int k = blk; k < blk + 32; ++k) {
      const int d = static_cast<int>(a[k]) - static_cast<int>(b[k]);
      s += d * d;
    }
    if (s > bound) return s;
  }
  return s;
}

// Image-2 keypoints bucketed by (d, s) = (n2 . x2, u2 . x2): counting sort into a regular grid.
struct Buckets {
  double d0 = 0, s0 = 0, bd = 8, bs = 32;
  int nd = 1, ns = 1;
  std::vector<int> start, items;
  std::vector<float> d, s;
  void build(const std::vector<cv::KeyPoint>& kp, const Eigen::Vector2d& n2, const Eigen::Vector2d& u2) {
    const size_t n = kp.size();
    d.resize(n);
    s.resize(n);
    double d1 = -1e300, s1 = -1e300;
    d0 = s0 = 1e300;
    for (size_t j = 0; j < n; ++j) {
      d[j] = static_cast<float>(n2.x() * kp[j].pt.x + n2.y() * kp[j].pt.y);
      s[j] = static_cast<float>(u2.x() * kp[j].pt.x + u2.y() * kp[j].pt.y);
      d0 = std::min(d0, static_cast<double>(d[j])), d1 = std::max(d1, static_cast<double>(d[j]));
      s0 = std::min(s0, static_cast<double>(s[j])), s1 = std::max(s1, static_cast<double>(s[j]));
    }
    nd = std::max(1, static_cast<int>((d1 - d0) / bd) + 1);
    ns = std::max(1, static_cast<int>((s1 - s0) / bs) + 1);
    start.assign(static_cast<size_t>(nd) * ns + 1, 0);
    for (size_t j = 0; j < n; ++j) ++start[cell(d[j], s[j]) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    items.resize(n);
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (size_t j = 0; j < n; ++j) items[fill[cell(d[j], s[j])]++] = static_cast<int>(j);  // ascending j per cell
  }
  size_t cell(double dv, double sv) const {
    int a = std::clamp(static_cast<int>((dv - d0) / bd), 0, nd - 1);
    int b = std::clamp(static_cast<int>((sv - s0) / bs), 0, ns - 1);
    return static_cast<size_t>(a) * ns + b;
  }
};

struct Best {
  int dist = std::numeric_limits<int>::max();
  int idx = -1;
};

}  // namespace

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
  const int G = std::max(1, g.coarse_grid);
  auto cell_of = [&](double x, double y) {
    int cx = std::clamp(static_cast<int>((x + 0.5) * G / std::max(1L, w1)), 0, G - 1);
    int cy = std::clamp(static_cast<int>((y + 0.5) * G / std::max(1L, h1)), 0, G - 1);
    return std::make_pair(cx, cy);
  };
  std::vector<std::vector<double>> per_cell(static_cast<size_t>(G) * G);
  for (size_t q = 0; q < in.size(); ++q) {
    auto [cx, cy] = cell_of(xy(in[q], 0), xy(in[q], 1));
    per_cell[static_cast<size_t>(cy) * G + cx].push_back(par(static_cast<Eigen::Index>(q)));
  }
  std::vector<double> lo(per_cell.size()), hi(per_cell.size());
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
      if (cnt < g.min_cell_samples) a = res.parallax_min, b = res.parallax_max;
      lo[static_cast<size_t>(cy) * G + cx] = a - g.parallax_margin;
      hi[static_cast<size_t>(cy) * G + cx] = b + g.parallax_margin;
    }

  // 2. guided search
  Buckets B;
  B.bd = std::max(4.0, g.band + g.ratio_margin);
  B.build(K2.kp, n2, u2);
  const int n1 = static_cast<int>(K1.kp.size()), n2k = static_cast<int>(K2.kp.size());
  const float ratio2 = static_cast<float>(desc.ratio * desc.ratio);
  std::vector<DescriptorMatch> fwd(static_cast<size_t>(n1), DescriptorMatch{-1, -1, 0.f, 0.f});
  const int W = std::max(1, std::min(threads, 64));
  std::vector<std::vector<Best>> back(static_cast<size_t>(W), std::vector<Best>(static_cast<size_t>(n2k)));
  std::vector<long long> compared(static_cast<size_t>(W), 0);
  const int chunk = 256;
  std::atomic<int> next{0};
  auto work = [&](int w) {
    std::vector<Best>& bk = back[static_cast<size_t>(w)];
    long long cmp = 0;
    for (;;) {
      const int b0 = next.fetch_add(chunk);
      if (b0 >= n1) break;
      for (int i = b0; i < std::min(n1, b0 + chunk); ++i) {
        const cv::Point2f p = K1.kp[static_cast<size_t>(i)].pt;
        auto [cx, cy] = cell_of(p.x, p.y);
        const size_t c = static_cast<size_t>(cy) * G + cx;
        const double dp = lc * p.x + ld * p.y + le;
        const double sp = plane(0) * p.x + plane(1) * p.y + plane(2);
        const double s_lo = sp + lo[c], s_hi = sp + hi[c];
        const double rd = g.band + g.ratio_margin;
        const double ws_lo = s_lo - g.ratio_margin, ws_hi = s_hi + g.ratio_margin;
        const int da = std::clamp(static_cast<int>(std::floor((dp - rd - B.d0) / B.bd)), 0, B.nd - 1);
        const int db = std::clamp(static_cast<int>(std::floor((dp + rd - B.d0) / B.bd)), 0, B.nd - 1);
        const int sa = std::clamp(static_cast<int>(std::floor((ws_lo - B.s0) / B.bs)), 0, B.ns - 1);
        const int sb = std::clamp(static_cast<int>(std::floor((ws_hi - B.s0) / B.bs)), 0, B.ns - 1);
        const uint8_t* q = K1.desc.ptr<uint8_t>(i);
        Best acc, m1, m2;  // best in the band; two best in the wider region
        for (int a = da; a <= db; ++a)
          for (int b = sa; b <= sb; ++b) {
            const size_t cb = static_cast<size_t>(a) * B.ns + b;
            for (int t = B.start[cb]; t < B.start[cb + 1]; ++t) {
              const int j = B.items[static_cast<size_t>(t)];
              const double dd = B.d[static_cast<size_t>(j)] - dp, ss = B.s[static_cast<size_t>(j)];
              if (std::abs(dd) > rd || ss < ws_lo || ss > ws_hi) continue;
              // a pair farther than both i's second best and j's best so far changes nothing
              Best& r = bk[static_cast<size_t>(j)];
              const int d2 = dist2_u8(q, K2.desc.ptr<uint8_t>(j), std::max(m2.dist, r.dist));
              ++cmp;
              if (d2 > m2.dist && d2 > r.dist) continue;
              if (d2 < m1.dist || (d2 == m1.dist && j < m1.idx)) {
                m2 = m1;
                m1 = {d2, j};
              } else if (d2 < m2.dist || (d2 == m2.dist && j < m2.idx)) {
                m2 = {d2, j};
              }
              if (std::abs(dd) <= g.band && ss >= s_lo && ss <= s_hi && (d2 < acc.dist || (d2 == acc.dist && j < acc.idx)))
                acc = {d2, j};
              if (d2 < r.dist || (d2 == r.dist && i < r.idx)) r = {d2, i};
            }
          }
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
  long long total = 0;
  for (long long c : compared) total += c;
  res.candidates_per_query = n1 > 0 ? static_cast<double>(total) / n1 : 0;
  for (const DescriptorMatch& m : fwd) {
    if (m.i1 < 0) continue;
    if (desc.mutual && bj[static_cast<size_t>(m.i2)].idx != m.i1) continue;
    res.matches.push_back(m);
  }
  res.ok = true;
  return res;
}

}  // namespace tpkit
