#include "tpkit/match/tracks_epipolar_check.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <optional>

#include "tpkit/core/error.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/match/rpc_guided_matching.hpp"

namespace tpkit {

namespace {

// Signed distance (pixels) of q from the polyline of the curve's points (x, y), run from its first
// point to its last: positive to the left; measured on the segment nearest to q.
std::optional<double> signed_distance(const std::vector<Eigen::Vector3d>& c, const Eigen::Vector2d& q) {
  if (c.size() < 2) return std::nullopt;
  double best = std::numeric_limits<double>::infinity(), sd = 0;
  for (size_t k = 0; k + 1 < c.size(); ++k) {
    const Eigen::Vector2d a = c[k].head<2>(), d = c[k + 1].head<2>() - a;
    const double L2 = d.squaredNorm();
    if (!(L2 > 1e-18)) continue;
    const double t = std::clamp((q - a).dot(d) / L2, 0.0, 1.0);
    const double dist = (a + t * d - q).norm();
    if (dist < best) {
      best = dist;
      sd = (d.x() * (q.y() - a.y()) - d.y() * (q.x() - a.x())) / std::sqrt(L2);
    }
  }
  if (!std::isfinite(best)) return std::nullopt;
  return sd;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  double x = v[m];
  if (v.size() % 2 == 0) x = 0.5 * (x + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m)));
  return x;
}

struct Sample {
  double x, y, d;  // view a's position, the signed distance of view b
};

// A pair's bias: a plane c0 x + c1 y + c2 (a constant below 10 tracks), fitted robustly; tol: the
// least residual that disagrees.
struct PairBias {
  bool judged = false;
  Eigen::Vector3d c{0, 0, 0};
  double sigma = 0, tol = 0, at_mean = 0;
  double operator()(double x, double y) const { return c(0) * x + c(1) * y + c(2); }
};

PairBias fit_bias(const std::vector<Sample>& s, double threshold) {
  PairBias b;
  if (s.size() < 3) return b;
  std::vector<double> d(s.size()), r(s.size());
  for (size_t i = 0; i < s.size(); ++i) d[i] = s[i].d;
  b.c = Eigen::Vector3d(0, 0, median(d));
  auto residuals = [&] {
    for (size_t i = 0; i < s.size(); ++i) r[i] = s[i].d - b(s[i].x, s[i].y);
  };
  auto robust_sigma = [&](const std::vector<double>& v) {
    const double m = median(v);
    std::vector<double> a(v.size());
    for (size_t i = 0; i < v.size(); ++i) a[i] = std::abs(v[i] - m);
    return 1.4826 * median(a);
  };
  for (int it = 0; it < 3; ++it) {
    residuals();
    const double keep = std::max(threshold, 3 * robust_sigma(r));
    std::vector<size_t> in;
    for (size_t i = 0; i < s.size(); ++i)
      if (std::abs(r[i]) <= keep) in.push_back(i);
    if (in.size() < 3) break;
    if (in.size() >= 10) {
      // centred on the kept samples' mean position (conditioning: pixels in the thousands)
      double mx = 0, my = 0;
      for (size_t i : in) mx += s[i].x, my += s[i].y;
      mx /= static_cast<double>(in.size()), my /= static_cast<double>(in.size());
      Eigen::MatrixX3d A(in.size(), 3);
      Eigen::VectorXd y(in.size());
      for (size_t k = 0; k < in.size(); ++k) {
        A.row(static_cast<Eigen::Index>(k)) << s[in[k]].x - mx, s[in[k]].y - my, 1.0;
        y(static_cast<Eigen::Index>(k)) = s[in[k]].d;
      }
      const Eigen::Vector3d p = A.colPivHouseholderQr().solve(y);
      b.c = Eigen::Vector3d(p(0), p(1), p(2) - p(0) * mx - p(1) * my);
    } else {
      double m = 0;
      for (size_t i : in) m += s[i].d;
      b.c = Eigen::Vector3d(0, 0, m / static_cast<double>(in.size()));
    }
  }
  residuals();
  b.sigma = robust_sigma(r);
  b.tol = std::max(threshold, 4 * b.sigma);
  double mx = 0, my = 0;
  for (const Sample& x : s) mx += x.x, my += x.y;
  b.at_mean = b(mx / static_cast<double>(s.size()), my / static_cast<double>(s.size()));
  b.judged = true;
  return b;
}

struct PairDistance {
  int a, b;
  double d;
};

}  // namespace

EpipolarCheckStats epipolar_check(Tracks& t, const std::vector<const RpcModel*>& models, const EpipolarCheckOptions& o) {
  const int K = t.views();
  if (static_cast<int>(models.size()) != K) throw std::invalid_argument("epipolar_check: one model per image");
  EpipolarCheckStats st;
  st.views_dropped_by_length.assign(static_cast<size_t>(K) + 1, 0);
  // the heights of each pair: those both models are valid for
  std::vector<double> lo(static_cast<size_t>(K * K)), hi(static_cast<size_t>(K * K));
  std::vector<char> usable(static_cast<size_t>(K * K), 0);
  for (int a = 0; a < K; ++a)
    for (int b = a + 1; b < K; ++b) {
      if (!models[static_cast<size_t>(a)] || !models[static_cast<size_t>(b)]) continue;
      try {
        const size_t ab = static_cast<size_t>(a * K + b);
        rpc_height_range(*models[static_cast<size_t>(a)], *models[static_cast<size_t>(b)], RpcGuideOptions{}, lo[ab], hi[ab]);
        usable[ab] = 1;
      } catch (const InputError&) {
      }
    }
  // 1. every pair of views of every track: the signed distance across the curve
  const size_t n = t.size();
  std::vector<std::vector<PairDistance>> dist(n);
  parallel_for(n, std::max(1, o.threads), [&](size_t r) {
    for (int a = 0; a < K; ++a) {
      if (!t.seen(r, a)) continue;
      const Eigen::Vector2d pa = t.point(r, a);
      for (int b = a + 1; b < K; ++b) {
        const size_t ab = static_cast<size_t>(a * K + b);
        if (!usable[ab] || !t.seen(r, b)) continue;
        const auto curve = epipolar_curve(*models[static_cast<size_t>(a)], *models[static_cast<size_t>(b)], pa.x(), pa.y(), lo[ab], hi[ab], 3);
        if (const auto d = signed_distance(curve, t.point(r, b))) dist[r].push_back({a, b, *d});
      }
    }
  });
  // 2. each pair's bias, robustly
  std::vector<std::vector<Sample>> samples(static_cast<size_t>(K * K));
  for (size_t r = 0; r < n; ++r)
    for (const PairDistance& p : dist[r]) {
      const Eigen::Vector2d pa = t.point(r, p.a);
      samples[static_cast<size_t>(p.a * K + p.b)].push_back({pa.x(), pa.y(), p.d});
    }
  std::vector<PairBias> bias(static_cast<size_t>(K * K));
  std::vector<double> sigmas;
  for (size_t ab = 0; ab < bias.size(); ++ab) {
    bias[ab] = fit_bias(samples[ab], o.threshold);
    if (!bias[ab].judged) continue;
    ++st.pairs_judged;
    sigmas.push_back(bias[ab].sigma);
    st.largest_bias = std::max(st.largest_bias, std::abs(bias[ab].at_mean));
  }
  st.median_sigma = median(sigmas);
  // 3. per track, the view that disagrees with the most others goes while any pair disagrees
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<char> keep_track(n, 1);
  std::vector<int> fails(static_cast<size_t>(K));
  std::vector<double> excess(static_cast<size_t>(K));
  std::vector<int> sigma_col(static_cast<size_t>(K), -1);
  for (int k = 0; k < K; ++k) sigma_col[static_cast<size_t>(k)] = t.extra.find("sigma" + std::to_string(k + 1));
  for (size_t r = 0; r < n; ++r) {
    const int views0 = t.seen_views(r);
    std::vector<char> out(static_cast<size_t>(K), 0);
    for (;;) {
      std::fill(fails.begin(), fails.end(), 0);
      std::fill(excess.begin(), excess.end(), 0.0);
      bool any = false;
      for (const PairDistance& p : dist[r]) {
        const PairBias& B = bias[static_cast<size_t>(p.a * K + p.b)];
        if (!B.judged || out[static_cast<size_t>(p.a)] || out[static_cast<size_t>(p.b)]) continue;
        const Eigen::Vector2d pa = t.point(r, p.a);
        const double e = std::abs(p.d - B(pa.x(), pa.y())) / B.tol;
        if (!(e > 1)) continue;
        any = true;
        for (int v : {p.a, p.b}) ++fails[static_cast<size_t>(v)], excess[static_cast<size_t>(v)] += e;
      }
      if (!any) break;
      int w = -1;
      for (int v = 0; v < K; ++v) {
        const size_t z = static_cast<size_t>(v);
        if (fails[z] == 0) continue;
        if (w < 0 || fails[z] > fails[static_cast<size_t>(w)] ||
            (fails[z] == fails[static_cast<size_t>(w)] && excess[z] >= excess[static_cast<size_t>(w)] * (1 - 1e-9)))
          w = v;
      }
      int left = 0;
      for (int v = 0; v < K; ++v) left += t.seen(r, v) && !out[static_cast<size_t>(v)];
      if (left <= 2) {  // two views that disagree: neither can be told right
        for (int v = 0; v < K; ++v) out[static_cast<size_t>(v)] = t.seen(r, v) ? 1 : 0;
        break;
      }
      out[static_cast<size_t>(w)] = 1;
    }
    int dropped = 0;
    for (int v = 0; v < K; ++v) {
      if (!out[static_cast<size_t>(v)]) continue;
      ++dropped;
      t.xy(static_cast<Eigen::Index>(r), 2 * v) = t.xy(static_cast<Eigen::Index>(r), 2 * v + 1) = nan;
      if (sigma_col[static_cast<size_t>(v)] >= 0) t.extra.values(static_cast<Eigen::Index>(r), sigma_col[static_cast<size_t>(v)]) = nan;
    }
    st.views_dropped += dropped;
    st.views_dropped_by_length[static_cast<size_t>(views0)] += dropped;
    if (views0 - dropped < std::max(2, o.min_views)) keep_track[r] = 0;
  }
  // 4. the tracks kept, ids from 0
  Eigen::Index w = 0;
  std::vector<long> line;
  for (size_t r = 0; r < n; ++r) {
    if (!keep_track[r]) {
      ++st.tracks_removed;
      continue;
    }
    t.xy.row(w) = t.xy.row(static_cast<Eigen::Index>(r));
    if (t.extra.values.rows() == static_cast<Eigen::Index>(n)) t.extra.values.row(w) = t.extra.values.row(static_cast<Eigen::Index>(r));
    if (t.line.size() == n) line.push_back(t.line[r]);
    ++w;
  }
  t.xy.conservativeResize(w, Eigen::NoChange);
  if (t.extra.values.rows() == static_cast<Eigen::Index>(n)) t.extra.values.conservativeResize(w, Eigen::NoChange);
  if (t.line.size() == n) t.line = std::move(line);
  t.id.resize(static_cast<size_t>(w));
  for (Eigen::Index k = 0; k < w; ++k) t.id[static_cast<size_t>(k)] = k;
  return st;
}

void note_epipolar_check(Tracks& t, const EpipolarCheckStats& st, double threshold) {
  auto two = [](double v) { return format_number(std::round(v * 100) / 100); };
  std::string by;
  for (size_t k = 0; k < st.views_dropped_by_length.size(); ++k)
    if (st.views_dropped_by_length[k] > 0) by += (by.empty() ? "" : " ") + std::to_string(k) + ":" + std::to_string(st.views_dropped_by_length[k]);
  meta_set(t.meta, "rpc_check",
           "views across the RPC epipolar curves of the others within max(" + two(threshold) +
               " px, 4 sigma of the pair) after each pair's bias (a plane); " + std::to_string(st.pairs_judged) +
               " image pairs, median sigma " + two(st.median_sigma) + " px, bias up to " + two(st.largest_bias) + " px; " +
               std::to_string(st.views_dropped) + " views dropped (by the track's views before: " + (by.empty() ? "none" : by) +
               "), " + std::to_string(st.tracks_removed) + " tracks removed");
  std::map<int, long> count;
  for (size_t r = 0; r < t.size(); ++r) count[t.seen_views(r)]++;
  std::string c;
  for (const auto& kv : count) c += (c.empty() ? "" : " ") + std::to_string(kv.first) + ":" + std::to_string(kv.second);
  meta_set(t.meta, "tracks_by_views", c.empty() ? "none" : c);
}

}  // namespace tpkit
