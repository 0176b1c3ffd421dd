#include "tpkit/match/sift_scale_space.hpp"

#include <algorithm>
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "tpkit/core/cpu_dispatch.hpp"
#include "tpkit/match/gaussian_blur.hpp"

namespace tpkit {

// Conventions: an octave's planes are CV_32F grey levels (0..255 of the 8-bit input); octave k (k = 0
// the upsampled one) has pixels 2^k upsampled pixels wide, and its pixel (c, r) is the input's
// (c 2^(k-1) - 0.25, r 2^(k-1) - 0.25). Layer l of an octave has the blur sigma 2^(l / layers) in
// octave pixels; D[l] = G[l + 1] - G[l]. Angles are in degrees; a gradient's orientation is
// atan2(I(y - 1) - I(y + 1), I(x + 1) - I(x - 1)) (y up, as OpenCV measures it), a keypoint's angle
// 360 minus its dominant orientation (OpenCV's KeyPoint::angle).
namespace {
constexpr int kBorder = 5;          // octave pixels at each edge where no extremum is sought
constexpr int kInterpSteps = 5;     // sub-pixel steps of an extremum before it is given up
// Farthest an extremum's sub-pixel steps may move it from the sample where it was found, in octave
// pixels (rows and columns each): so that the extrema of a region are those found within this margin
// of it, and a tile's keypoints do not depend on how far its overlap reaches. Lowe's steps have no such
// bound: it drops 742 of the 10000² synthetic pair's 3.8 million keypoints (0.02%), 2 of Marseille
// img_01's 24 305.
constexpr int kMaxTravel = 6;
constexpr double kInputBlur = 0.5;  // blur assumed in the input image, pixels
constexpr int kOriBins = 36;
constexpr float kOriSigma = 1.5f;   // orientation window: Gaussian of 1.5 scales, radius 3 of its sigmas
constexpr float kOriRadius = 3 * kOriSigma;
constexpr float kOriPeak = 0.8f;    // further orientations: local peaks above 0.8 x the highest
constexpr int kAhead = 5;            // window rows asked for ahead of their use (ask_rows)
constexpr int kCells = 4, kBins = 8;  // descriptor: kCells x kCells cells of kBins orientations
constexpr float kCellWidth = 3.f;     // a cell's width, in scales
constexpr float kClamp = 0.2f;        // entries clamped at 0.2 x the descriptor's norm, then renormalised
constexpr float kDescriptorNorm = 512.f;
constexpr float kGrey = 1.f / 255;    // D and its derivatives on grey levels / 255

// The number of strips of a plane of `rows` rows: fixed by the size, so results do not depend on threads.
int strip_count(int rows) { return std::max(1, std::min(64, rows / 32)); }

// f(strip, first row, end row) over rows [0, rows) in strip_count(rows) strips, on OpenCV's pool.
template <class F>
void by_strips(int rows, F&& f) {
  const int n = strip_count(rows);
  cv::parallel_for_(cv::Range(0, n), [&](const cv::Range& R) {
    for (int s = R.start; s < R.end; ++s)
      f(s, static_cast<int>(static_cast<long>(rows) * s / n), static_cast<int>(static_cast<long>(rows) * (s + 1) / n));
  });
}

// every second pixel of every second row: the next octave's first layer
cv::Mat decimated(const cv::Mat& g) {
  cv::Mat d(g.rows / 2, g.cols / 2, CV_32F);
  for (int r = 0; r < d.rows; ++r) {
    const float* s = g.ptr<float>(2 * r);
    float* o = d.ptr<float>(r);
    for (int c = 0; c < d.cols; ++c) o[c] = s[2 * c];
  }
  return d;
}

struct Extremum {
  int layer, r, c;      // octave pixel and layer after the sub-pixel steps
  float xc, xr, xi;     // sub-pixel offsets (columns, rows, layers), each below 0.5
  float contrast;       // |D| at the interpolated extremum (grey levels / 255)
};

// First and second derivatives of D (grey levels / 255) at sample (layer, r, c) by central differences.
struct Derivatives {
  float v, dx, dy, ds, dxx, dyy, dss, dxy, dxs, dys;
};

Derivatives derivatives(const std::vector<cv::Mat>& G, int layer, int r, int c) {
  auto at = [&](int l, int y, int x) { return G[l + 1].ptr<float>(y)[x] - G[l].ptr<float>(y)[x]; };  // D[l]
  Derivatives d;
  d.v = at(layer, r, c);
  d.dx = (at(layer, r, c + 1) - at(layer, r, c - 1)) * 0.5f * kGrey;
  d.dy = (at(layer, r + 1, c) - at(layer, r - 1, c)) * 0.5f * kGrey;
  d.ds = (at(layer + 1, r, c) - at(layer - 1, r, c)) * 0.5f * kGrey;
  d.dxx = (at(layer, r, c + 1) + at(layer, r, c - 1) - 2 * d.v) * kGrey;
  d.dyy = (at(layer, r + 1, c) + at(layer, r - 1, c) - 2 * d.v) * kGrey;
  d.dss = (at(layer + 1, r, c) + at(layer - 1, r, c) - 2 * d.v) * kGrey;
  d.dxy = (at(layer, r + 1, c + 1) - at(layer, r + 1, c - 1) - at(layer, r - 1, c + 1) + at(layer, r - 1, c - 1)) * 0.25f * kGrey;
  d.dxs = (at(layer + 1, r, c + 1) - at(layer + 1, r, c - 1) - at(layer - 1, r, c + 1) + at(layer - 1, r, c - 1)) * 0.25f * kGrey;
  d.dys = (at(layer + 1, r + 1, c) - at(layer + 1, r - 1, c) - at(layer - 1, r + 1, c) + at(layer - 1, r - 1, c)) * 0.25f * kGrey;
  return d;
}

// Lowe's interpolation of a scale-space extremum: Newton steps on the quadratic fit of D, moving to the
// neighbouring sample while an offset exceeds half a sample (kMaxTravel from the start at most); then
// the contrast and edge tests at the sample where the steps settled.
bool interpolate(const std::vector<cv::Mat>& G, int layers, const ScaleSpaceOptions& o, int layer, int r, int c, Extremum& e) {
  const int rows = G[0].rows, cols = G[0].cols, r_start = r, c_start = c;
  float xi = 0, xr = 0, xc = 0;
  Derivatives d{};
  int step = 0;
  for (; step < kInterpSteps; ++step) {
    d = derivatives(G, layer, r, c);
    // offset X = -H^-1 dD by Cramer's rule (H symmetric); a singular H gives no step
    const double a = d.dxx, b = d.dxy, cc = d.dxs, dd = d.dyy, f = d.dys, g = d.dss;
    const double det = a * (dd * g - f * f) - b * (b * g - f * cc) + cc * (b * f - dd * cc);
    if (det != 0 && std::isfinite(det)) {
      const double i00 = dd * g - f * f, i01 = cc * f - b * g, i02 = b * f - cc * dd;
      const double i11 = a * g - cc * cc, i12 = b * cc - a * f, i22 = a * dd - b * b;
      xc = static_cast<float>(-(i00 * d.dx + i01 * d.dy + i02 * d.ds) / det);
      xr = static_cast<float>(-(i01 * d.dx + i11 * d.dy + i12 * d.ds) / det);
      xi = static_cast<float>(-(i02 * d.dx + i12 * d.dy + i22 * d.ds) / det);
    } else {
      xc = xr = xi = 0;
    }
    if (std::abs(xi) < 0.5f && std::abs(xr) < 0.5f && std::abs(xc) < 0.5f) break;
    if (!(std::abs(xi) < INT_MAX / 3.f && std::abs(xr) < INT_MAX / 3.f && std::abs(xc) < INT_MAX / 3.f)) return false;
    c += cvRound(xc);
    r += cvRound(xr);
    layer += cvRound(xi);
    if (layer < 1 || layer > layers || c < kBorder || c >= cols - kBorder || r < kBorder || r >= rows - kBorder) return false;
    if (std::abs(c - c_start) > kMaxTravel || std::abs(r - r_start) > kMaxTravel) return false;
  }
  if (step >= kInterpSteps) return false;
  const float contr = d.v * kGrey + 0.5f * (d.dx * xc + d.dy * xr + d.ds * xi);
  if (std::abs(contr) * layers < o.contrast) return false;
  // edges: the ratio of the principal curvatures from the trace and determinant of the 2 x 2 Hessian
  const float tr = d.dxx + d.dyy, det = d.dxx * d.dyy - d.dxy * d.dxy;
  const float edge = static_cast<float>(o.edge);
  if (det <= 0 || tr * tr * edge >= (edge + 1) * (edge + 1) * det) return false;
  e = {layer, r, c, xc, xr, xi, std::abs(contr)};
  return true;
}

// The 26-neighbour test, separably. For a D layer k, M[k] at (r, c) is the largest of the 3 x 3
// samples around it (the largest of three rows' largest of three columns), m[k] the smallest; a sample v
// of layer l is at least each of its 26 neighbours iff v >= M[l - 1], M[l] (which holds v itself) and
// M[l + 1] there, and at most each iff v <= m[l - 1], m[l], m[l + 1]. Each layer's M and m are computed
// once per row and serve the three layers that read them: about half the comparisons of testing each
// sample's 26 neighbours, the same candidates.

// hi[c], lo[c] = max, min of p[c - 1], p[c], p[c + 1], for c in [c0, c1).
void max_min3(const float* __restrict p, int c0, int c1, float* __restrict hi, float* __restrict lo) {
  for (int c = c0; c < c1; ++c) {
    hi[c] = std::max(std::max(p[c - 1], p[c]), p[c + 1]);
    lo[c] = std::min(std::min(p[c - 1], p[c]), p[c + 1]);
  }
}

// hi[c], lo[c] = max of a[c], b[c], e[c] and min of f[c], g[c], h[c], for c in [c0, c1).
void max_min_rows(const float* __restrict a, const float* __restrict b, const float* __restrict e, const float* __restrict f,
                  const float* __restrict g, const float* __restrict h, int c0, int c1, float* __restrict hi, float* __restrict lo) {
  for (int c = c0; c < c1; ++c) {
    hi[c] = std::max(std::max(a[c], b[c]), e[c]);
    lo[c] = std::min(std::min(f[c], g[c]), h[c]);
  }
}

// cand[c] = 1 where v[c] (a sample of D layer l) is an extremum of its 26 neighbours beyond the
// pre-threshold (v >= each of them for a maximum, <= for a minimum), M and m those of layers l - 1, l,
// l + 1, for c in [c0, c1): a branch-free loop the compiler vectorises, so that only the extrema reach
// the branches of the interpolation.
void cube_candidates(const float* __restrict v, const float* const M[3], const float* const m[3], int c0, int c1, float threshold,
                     uint8_t* __restrict cand) {
  const float *__restrict M0 = M[0], *__restrict M1 = M[1], *__restrict M2 = M[2];
  const float *__restrict m0 = m[0], *__restrict m1 = m[1], *__restrict m2 = m[2];
  for (int c = c0; c < c1; ++c) {
    const float x = v[c];
    const bool up = (x > threshold) & (x > 0.f) & (x >= M0[c]) & (x >= M1[c]) & (x >= M2[c]);
    const bool down = (x < -threshold) & (x < 0.f) & (x <= m0[c]) & (x <= m1[c]) & (x <= m2[c]);
    cand[c] = static_cast<uint8_t>(up | down);
  }
}

// Octave pixels [c0, c1) x [r0, r1) where extrema are sought.
struct Window {
  int c0, c1, r0, r1;
};

// Extrema of D over its 26 neighbours in layers 1..layers (D from the Gaussian layers G) whose sample
// lies in `win`, interpolated; in row order, layer by layer. One pass down the rows keeps rows r - 1, r,
// r + 1 of every D layer (over the window's columns and one more on each side) and of their maxima and
// minima.
std::vector<Extremum> extrema(const std::vector<cv::Mat>& G, int layers, const ScaleSpaceOptions& o, const Window& win) {
  const int rows = G[0].rows, nd = layers + 2;  // D[k] = G[k + 1] - G[k], k = 0..layers + 1
  std::vector<Extremum> out;
  if (win.c0 >= win.c1 || win.r0 >= win.r1) return out;
  // OpenCV's pre-threshold on |D| (grey levels; 0 for contrast thresholds below 0.06 with 3 layers)
  const float threshold = static_cast<float>(std::floor(0.5 * o.contrast / layers * 255));
  // found[l][strip]
  std::vector<std::vector<std::vector<Extremum>>> found(layers + 1, std::vector<std::vector<Extremum>>(strip_count(rows)));
  by_strips(rows, [&](int s, int a, int b) {
    const int r0 = std::max(a, win.r0), r1 = std::min(b, win.r1);
    if (r0 >= r1) return;
    // slot (y - r0 + 1) % 3 holds row y of every D layer over columns [x0, x1), and its rows' maxima and
    // minima over [c0, c1); M and m (rmax, rmin over three rows) are row r's. Each is computed once; the
    // pointers are shifted so that they index by octave column.
    const int c0 = win.c0, c1 = win.c1, x0 = c0 - 1, x1 = c1 + 1, w = x1 - x0, cw = c1 - c0;
    std::vector<float> ring(3 * static_cast<size_t>(nd) * (w + 2 * cw) + 2 * static_cast<size_t>(nd) * cw);
    std::vector<uint8_t> cand(x1);
    float* const rmax0 = ring.data() + 3 * static_cast<size_t>(nd) * w;
    float* const rmin0 = rmax0 + 3 * static_cast<size_t>(nd) * cw;
    float* const M0 = rmin0 + 3 * static_cast<size_t>(nd) * cw;
    float* const m0 = M0 + static_cast<size_t>(nd) * cw;
    auto at = [&](int y, int k) { return static_cast<size_t>((y - r0 + 1) % 3) * nd + k; };
    auto d_row = [&](int y, int k) { return ring.data() + at(y, k) * w - x0; };
    auto rmax = [&](int y, int k) { return rmax0 + at(y, k) * cw - c0; };
    auto rmin = [&](int y, int k) { return rmin0 + at(y, k) * cw - c0; };
    auto fill_rows = [&](int y) {
      if (y + 1 < rows)  // the next row of each layer asked for now: the layers are planes of megabytes
        for (int k = 0; k <= nd; ++k) prefetch_floats(G[k].ptr<float>(y + 1) + x0, x1 - x0);
      for (int k = 0; k < nd; ++k) {
        const float *hi = G[k + 1].ptr<float>(y), *lo = G[k].ptr<float>(y);
        float* to = d_row(y, k);
        for (int c = x0; c < x1; ++c) to[c] = hi[c] - lo[c];
        max_min3(to, c0, c1, rmax(y, k), rmin(y, k));
      }
    };
    fill_rows(r0 - 1);
    fill_rows(r0);
    for (int r = r0; r < r1; ++r) {
      fill_rows(r + 1);
      for (int k = 0; k < nd; ++k)
        max_min_rows(rmax(r - 1, k), rmax(r, k), rmax(r + 1, k), rmin(r - 1, k), rmin(r, k), rmin(r + 1, k), c0, c1,
                     M0 + static_cast<size_t>(k) * cw - c0, m0 + static_cast<size_t>(k) * cw - c0);
      for (int l = 1; l <= layers; ++l) {
        const float* M[3];
        const float* m[3];
        for (int n = 0; n < 3; ++n) {
          M[n] = M0 + static_cast<size_t>(l - 1 + n) * cw - c0;
          m[n] = m0 + static_cast<size_t>(l - 1 + n) * cw - c0;
        }
        cube_candidates(d_row(r, l), M, m, c0, c1, threshold, cand.data());
        const int end = win.c1;
        for (int c = win.c0; c < end; ++c) {
          uint64_t eight;  // the candidates are rare: skip 8 columns at a time
          while (c + 8 <= end && (std::memcpy(&eight, cand.data() + c, 8), eight == 0)) c += 8;
          if (c >= end) break;
          if (!cand[c]) continue;
          Extremum e;
          if (interpolate(G, layers, o, l, r, c, e)) found[l][s].push_back(e);
        }
      }
    }
  });
  for (int l = 1; l <= layers; ++l)
    for (auto& f : found[l]) out.insert(out.end(), f.begin(), f.end());
  return out;
}

// Gradient magnitude and orientation of the pixels of a Gaussian layer in `box` (zero on the plane's
// one-pixel border); the pixels outside the box are not set.
struct Gradients {
  cv::Mat mag, ori;
};

// Asks the memory for row y of both maps over columns [x0, x1] and returns at once (one request per
// cache line). A window's rows lie a plane's width apart in the maps, and waiting for each row's lines
// took a fifth of the descriptors' time and two fifths of the orientations': their loops ask for a row
// kAhead rows before they read it (for the window's first rows, before the loop).
inline void ask_rows(const Gradients& G, int y, int x0, int x1) {
  prefetch_floats(G.mag.ptr<float>(y) + x0, x1 - x0 + 1);
  prefetch_floats(G.ori.ptr<float>(y) + x0, x1 - x0 + 1);
}

Gradients gradients(const cv::Mat& g, cv::Rect box) {
  const int rows = g.rows, cols = g.cols;
  Gradients out{cv::Mat(g.size(), CV_32F), cv::Mat(g.size(), CV_32F)};
  box &= cv::Rect(0, 0, cols, rows);
  // the interior columns computed: OpenCV's vector loops give a row's every value the same way when the
  // row holds two vectors at least (its tail is a vector overlapping the last), so a box no narrower
  // than 32 gives the values of the whole row
  int x0 = std::max(1, box.x), x1 = std::min(cols - 1, box.x + box.width);
  if (x1 - x0 < 32) x0 = 1, x1 = cols - 1;
  by_strips(rows, [&](int, int a, int b) {
    a = std::max(a, box.y);
    b = std::min(b, box.y + box.height);
    std::vector<float> dx(cols), dy(cols);
    for (int y = a; y < b; ++y) {
      float *m = out.mag.ptr<float>(y), *t = out.ori.ptr<float>(y);
      if (y == 0 || y == rows - 1 || cols < 3) {
        std::fill(m, m + cols, 0.f);
        std::fill(t, t + cols, 0.f);
        continue;
      }
      const float *p = g.ptr<float>(y), *up = g.ptr<float>(y - 1), *dn = g.ptr<float>(y + 1);
      for (int x = x0; x < x1; ++x) {
        dx[x] = p[x + 1] - p[x - 1];
        dy[x] = up[x] - dn[x];
      }
      cv::hal::magnitude32f(dx.data() + x0, dy.data() + x0, m + x0, x1 - x0);
      cv::hal::fastAtan32f(dy.data() + x0, dx.data() + x0, t + x0, x1 - x0, true);
      m[0] = m[cols - 1] = t[0] = t[cols - 1] = 0.f;
    }
  });
  return out;
}

// Dominant orientations (degrees) at octave pixel (px, py) of scale `scl`: the peaks of the smoothed
// 36-bin histogram of gradient orientations weighted by magnitude and a Gaussian of 1.5 scales, each
// refined by a parabola through its bin and the two beside it.
int orientations(const Gradients& G, int px, int py, float scl, float* peaks) {
  const int rows = G.mag.rows, cols = G.mag.cols;
  const int R = cvRound(kOriRadius * scl);
  const float sig = kOriSigma * scl, k = -1.f / (2 * sig * sig);
  thread_local std::vector<float> wt;
  wt.resize(2 * static_cast<size_t>(R) + 1);
  float* w = wt.data() + R;
  for (int i = -R; i <= R; ++i) w[i] = std::exp(static_cast<float>(i * i) * k);
  float raw[kOriBins + 4] = {};
  float* h = raw + 2;
  const int x0 = std::max(1, px - R), x1 = std::min(cols - 2, px + R);
  for (int i = -R; i <= std::min(R, -R + kAhead - 1); ++i)
    if (py + i > 0 && py + i < rows - 1) ask_rows(G, py + i, x0, x1);
  for (int i = -R; i <= R; ++i) {
    const int y = py + i;
    if (y <= 0 || y >= rows - 1) continue;
    if (i + kAhead <= R && y + kAhead < rows - 1) ask_rows(G, y + kAhead, x0, x1);
    const float *m = G.mag.ptr<float>(y), *t = G.ori.ptr<float>(y);
    for (int x = x0; x <= x1; ++x) {
      int bin = cvRound(t[x] * (kOriBins / 360.f));
      if (bin >= kOriBins) bin -= kOriBins;
      if (bin < 0) bin += kOriBins;
      h[bin] += w[i] * w[x - px] * m[x];
    }
  }
  h[-1] = h[kOriBins - 1];
  h[-2] = h[kOriBins - 2];
  h[kOriBins] = h[0];
  h[kOriBins + 1] = h[1];
  float s[kOriBins];
  for (int i = 0; i < kOriBins; ++i) s[i] = (h[i - 2] + h[i + 2]) * (1.f / 16) + (h[i - 1] + h[i + 1]) * (4.f / 16) + h[i] * (6.f / 16);
  const float top = *std::max_element(s, s + kOriBins), thr = top * kOriPeak;
  int n = 0;
  for (int j = 0; j < kOriBins; ++j) {
    const int l = j > 0 ? j - 1 : kOriBins - 1, r = j < kOriBins - 1 ? j + 1 : 0;
    if (s[j] > s[l] && s[j] > s[r] && s[j] >= thr) {
      float bin = j + 0.5f * (s[l] - s[r]) / (s[l] - 2 * s[j] + s[r]);
      bin = bin < 0 ? kOriBins + bin : bin >= kOriBins ? bin - kOriBins : bin;
      peaks[n++] = bin * (360.f / kOriBins);
    }
  }
  return n;
}

// The interval of u where a u + b lies in (-1, kCells), intersected with [lo, hi]; false when empty.
bool cell_span(float a, float b, float& lo, float& hi) {
  if (std::abs(a) < 1e-12f) return b > -1 && b < kCells;
  float u0 = (-1 - b) / a, u1 = (kCells - b) / a;
  if (u0 > u1) std::swap(u0, u1);
  lo = std::max(lo, u0);
  hi = std::min(hi, u1);
  return lo <= hi;
}

constexpr int kRow = kCells + 2, kHist = kRow * kRow * (kBins + 2);  // descriptor histogram with a border cell

// floor(x) for |x| < 2^31, in operations a vector unit has (truncation, compare): the compiler vectorises
// the loops that use it, where std::floor needs SSE4.1.
inline int floor_int(float x) {
  const int i = static_cast<int>(x);
  return i - static_cast<int>(x < static_cast<float>(i));
}

// Descriptor windows sample every second pixel of their octave, in rows and columns: a window spans
// 4 x 3 sigma >= 24 octave pixels over gradient maps blurred by sigma >= 2 octave pixels, so every second
// sample holds what the map has (in the upsampled octave, these are the input's own pixels). A quarter
// of the samples; against every pixel in octaves 0 and up (the upsampled octave was sampled so already),
// Marseille pair 1-2 detection at 1 thread 0.915 -> 0.866 s, the triplet's ML fit 7707 -> 7709 triplets
// at 0.1010 -> 0.0990 px, the synthetic scenes' errors the same (0.0671 / 0.1844 px, 4921 triplets
// instead of 4933; relief 0.0186 / 0.0475 px).
constexpr int kStride = 2;

// One row of a descriptor window, samples k = 0..n-1 at every kStride-th pixel from the row's first, in a
// loop the compiler vectorises: the sample's histogram entry (cell row, cell column, orientation bin:
// the first of the 8 it spreads over), its fractional parts there and its weighted magnitude (0 for a
// sample outside the cells, whose entry is then 0).
void row_bins(const float* __restrict m, const float* __restrict t, const float* __restrict wx, int n, float ca, float sa, float c0,
              float r0, float ori, float per_degree, float wy, int* __restrict at, float* __restrict dr, float* __restrict dc,
              float* __restrict dob, float* __restrict mg) {
  for (int k = 0; k < n; ++k) {
    const float u = static_cast<float>(kStride * k);
    const float cbin = c0 + u * ca, rbin = r0 + u * sa, obin = (t[kStride * k] - ori) * per_degree;
    const int inside = static_cast<int>(rbin > -1) & static_cast<int>(rbin < kCells) & static_cast<int>(cbin > -1) &
                       static_cast<int>(cbin < kCells);
    const int ri = floor_int(rbin), ci = floor_int(cbin), oi = floor_int(obin);
    const int o0 = oi + kBins * static_cast<int>(oi < 0) - kBins * static_cast<int>(oi >= kBins);
    dr[k] = rbin - static_cast<float>(ri);
    dc[k] = cbin - static_cast<float>(ci);
    dob[k] = obin - static_cast<float>(oi);
    at[k] = (((ri + 1) * kRow + ci + 1) * (kBins + 2) + o0) & -inside;
    mg[k] = m[kStride * k] * wx[kStride * k] * wy * static_cast<float>(inside);
  }
}

// The radius of the descriptor window of a keypoint of scale `scl` (octave pixels): the rotated cells and
// their half-cell border (larger than the orientation window's).
int descriptor_radius(float scl) { return cvRound(kCellWidth * scl * 1.4142135623730951f * (kCells + 1) * 0.5f); }

// The 4 x 4 x 8 descriptor at octave position (x, y) of scale `scl` and orientation `ori` (degrees):
// magnitudes weighted by a Gaussian of half the window's width, spread trilinearly over the cells and
// orientation bins; clamped at 0.2 of the norm, renormalised, scaled to 512 and saturated at 255.
void descriptor(const Gradients& G, float x, float y, float ori, float scl, float* out) {
  const int rows = G.mag.rows, cols = G.mag.cols;
  const float width = kCellWidth * scl;
  int R = descriptor_radius(scl);
  R = std::min(R, static_cast<int>(std::sqrt(static_cast<double>(rows) * rows + static_cast<double>(cols) * cols)));
  const int px = cvRound(x), py = cvRound(y);
  const float fx = x - px, fy = y - py;
  const float ca = std::cos(ori * static_cast<float>(CV_PI / 180)) / width, sa = std::sin(ori * static_cast<float>(CV_PI / 180)) / width;
  // weight exp(-|rotated offset / width|^2 / (d^2 / 2)): separable in the unrotated offsets
  const float k = -1.f / (0.5f * kCells * kCells * width * width);
  thread_local std::vector<float> wxs, wys;
  wxs.resize(2 * R + 1);
  wys.resize(2 * R + 1);
  for (int i = -R; i <= R; ++i) {
    wxs[i + R] = std::exp((i - fx) * (i - fx) * k);
    wys[i + R] = std::exp((i - fy) * (i - fy) * k);
  }
  float hist[kHist] = {};
  const float half = kCells / 2.f - 0.5f, per_degree = kBins / 360.f;
  thread_local std::vector<float> buf;
  thread_local std::vector<int> entry;
  buf.resize(4 * static_cast<size_t>(2 * R + 1));
  entry.resize(static_cast<size_t>(2 * R + 1));
  float *dr = buf.data(), *dc = dr + (2 * R + 1), *dob = dc + (2 * R + 1), *mg = dob + (2 * R + 1);
  int* at = entry.data();
  const int xa = std::max(0, px - R), xb = std::min(cols - 1, px + R), ahead = kAhead * kStride;
  for (int i = -R; i <= std::min(R, -R + ahead - kStride); i += kStride)
    if (py + i > 0 && py + i < rows - 1) ask_rows(G, py + i, xa, xb);
  for (int i = -R; i <= R; i += kStride) {
    const int yy = py + i;
    if (yy <= 0 || yy >= rows - 1) continue;
    if (i + ahead <= R && yy + ahead < rows - 1) ask_rows(G, yy + ahead, xa, xb);
    const float v = i - fy;
    // columns whose rotated position lies in the cells: cbin = u ca - v sa + half, rbin = u sa + v ca + half
    float lo = static_cast<float>(std::max(-R, 1 - px)) - fx, hi = static_cast<float>(std::min(R, cols - 2 - px)) - fx;
    if (!cell_span(ca, half - v * sa, lo, hi) || !cell_span(sa, half + v * ca, lo, hi)) continue;
    const int j0 = std::max(std::max(-R, 1 - px), static_cast<int>(std::floor(lo + fx))),
              j1 = std::min(std::min(R, cols - 2 - px), static_cast<int>(std::ceil(hi + fx)));
    const int js = (j0 + 1) & ~1;  // even offsets: the same grid in every row
    if (j1 < js) continue;
    const int n = (j1 - js) / kStride + 1;
    const float *m = G.mag.ptr<float>(yy) + px + js, *t = G.ori.ptr<float>(yy) + px + js, *wx = wxs.data() + R + js;
    // the row's entries and weights, vectorised; then the scatter (a sample outside adds zeros to entry 0)
    const float wy = wys[i + R], c0v = (js - fx) * ca - v * sa + half, r0v = (js - fx) * sa + v * ca + half;
    row_bins(m, t, wx, n, ca, sa, c0v, r0v, ori, per_degree, wy, at, dr, dc, dob, mg);
    for (int k = 0; k < n; ++k) {
      const float mag = mg[k];
      const float v1 = mag * dr[k], v0 = mag - v1;
      const float v11 = v1 * dc[k], v10 = v1 - v11, v01 = v0 * dc[k], v00 = v0 - v01;
      const float d = dob[k];
      const float v111 = v11 * d, v110 = v11 - v111, v101 = v10 * d, v100 = v10 - v101;
      const float v011 = v01 * d, v010 = v01 - v011, v001 = v00 * d, v000 = v00 - v001;
      float* p = hist + at[k];
      p[0] += v000;
      p[1] += v001;
      p[kBins + 2] += v010;
      p[kBins + 3] += v011;
      p[kRow * (kBins + 2)] += v100;
      p[kRow * (kBins + 2) + 1] += v101;
      p[(kRow + 1) * (kBins + 2)] += v110;
      p[(kRow + 1) * (kBins + 2) + 1] += v111;
    }
  }
  // fold the orientation wrap-around, keep the inner cells
  for (int i = 0; i < kCells; ++i)
    for (int j = 0; j < kCells; ++j) {
      float* p = hist + ((i + 1) * kRow + j + 1) * (kBins + 2);
      p[0] += p[kBins];
      p[1] += p[kBins + 1];
      for (int b = 0; b < kBins; ++b) out[(i * kCells + j) * kBins + b] = p[b];
    }
  constexpr int kLen = kCells * kCells * kBins;
  float n2 = 0;
  for (int b = 0; b < kLen; ++b) n2 += out[b] * out[b];
  const float cap = std::sqrt(n2) * kClamp;
  n2 = 0;
  for (int b = 0; b < kLen; ++b) {
    out[b] = std::min(out[b], cap);
    n2 += out[b] * out[b];
  }
  const float scale = kDescriptorNorm / std::max(std::sqrt(n2), FLT_EPSILON);
  for (int b = 0; b < kLen; ++b) out[b] = static_cast<float>(cv::saturate_cast<uint8_t>(out[b] * scale));
}

// A keypoint of one octave before its descriptor: where to sample (octave pixels) and the output fields.
struct Oriented {
  cv::KeyPoint kp;
  float x, y, scl, ori;  // octave position, scale (octave pixels), descriptor orientation (degrees)
};

bool same_keypoint(const cv::KeyPoint& a, const cv::KeyPoint& b) {
  return a.pt.x == b.pt.x && a.pt.y == b.pt.y && a.size == b.size && a.angle == b.angle;
}

// The blur added from layer i - 1 to layer i of an octave (i >= 1; total blur sigma 2^(i / L)).
std::vector<double> layer_steps(const ScaleSpaceOptions& o) {
  const int L = o.octave_layers;
  std::vector<double> step(L + 3);
  const double k = std::pow(2.0, 1.0 / L);
  for (int i = 1; i < L + 3; ++i) {
    const double prev = std::pow(k, i - 1) * o.sigma, total = prev * k;
    step[i] = std::sqrt(total * total - prev * prev);
  }
  return step;
}

// The first octave's first layer: the image upsampled twice (its blur then 2 x 0.5 upsampled pixels),
// blurred to sigma.
cv::Mat first_octave(const cv::Mat& image, double sigma) {
  cv::Mat f, up;
  image.convertTo(f, CV_32F);
  cv::resize(f, up, cv::Size(image.cols * 2, image.rows * 2), 0, 0, cv::INTER_LINEAR);
  return gaussian_blur(up, std::sqrt(std::max(sigma * sigma - 4 * kInputBlur * kInputBlur, 0.01)));
}

// An extremum of octave `oc`: its position in the input's pixels and its scale in octave pixels.
float to_image(int oc) { return std::ldexp(1.f, oc - 1); }  // octave pixels -> input pixels

cv::Point2f image_position(const Extremum& e, int oc) {
  return {(e.c + e.xc) * to_image(oc) - 0.25f, (e.r + e.xr) * to_image(oc) - 0.25f};
}

float octave_scale(const Extremum& e, const ScaleSpaceOptions& o) {
  return static_cast<float>(o.sigma * std::pow(2.0, (e.layer + e.xi) / o.octave_layers));
}

// Octave pixels where extrema of octave `oc` (planes of `size`) are sought: those within kMaxTravel of
// the wanted region, and kBorder from the edges.
Window scan_window(const ScaleSpaceOptions::Region& region, int oc, cv::Size size) {
  const double s = to_image(oc);
  auto clamped = [](double v, int lo, int hi) { return static_cast<int>(std::clamp(v, static_cast<double>(lo), static_cast<double>(hi))); };
  const int cmax = std::max(kBorder, size.width - kBorder), rmax = std::max(kBorder, size.height - kBorder);
  return {clamped(std::floor((region.x0 + 0.25) / s) - kMaxTravel, kBorder, cmax),
          clamped(std::ceil((region.x1 + 0.25) / s) + kMaxTravel + 1, kBorder, cmax),
          clamped(std::floor((region.y0 + 0.25) / s) - kMaxTravel, kBorder, rmax),
          clamped(std::ceil((region.y1 + 0.25) / s) + kMaxTravel + 1, kBorder, rmax)};
}

// The pixels of each Gaussian layer of an octave (planes of `size`) that are read: the whole plane for
// layers 0..L (the next octave starts from layer L, the descriptors read 1..L), and for the top two, which
// only the extremum search reads, the scan window with the interpolation's reach (kMaxTravel and a
// neighbour), layer L + 1 also with the blur's support of layer L + 2. On a 1216² tile's first octave
// they are 75% and 73% of the plane, for its two widest blurs.
std::vector<cv::Rect> layer_rects(const Window& win, cv::Size size, const std::vector<double>& step) {
  const int L = static_cast<int>(step.size()) - 3;
  const cv::Rect plane(0, 0, size.width, size.height);
  std::vector<cv::Rect> need(L + 3, plane);
  auto grown = [&](const cv::Rect& r, int m) { return cv::Rect(r.x - m, r.y - m, r.width + 2 * m, r.height + 2 * m) & plane; };
  need[L + 2] = grown(cv::Rect(win.c0, win.r0, std::max(0, win.c1 - win.c0), std::max(0, win.r1 - win.r0)), kMaxTravel + 1);
  need[L + 1] = grown(need[L + 2], gaussian_blur_radius(step[L + 2]));
  return need;
}

// The octave pixels that the orientation histograms and descriptors of the extrema `at` read.
cv::Rect window_box(const std::vector<Extremum>& ext, const std::vector<int>& at, const ScaleSpaceOptions& o) {
  int c0 = INT_MAX, c1 = INT_MIN, r0 = INT_MAX, r1 = INT_MIN, reach = 0;
  for (int i : at) {
    const Extremum& e = ext[i];
    c0 = std::min(c0, e.c), c1 = std::max(c1, e.c), r0 = std::min(r0, e.r), r1 = std::max(r1, e.r);
    // the descriptor's window around the nearest pixel (+-1 of the sample)
    reach = std::max(reach, descriptor_radius(octave_scale(e, o)) + 1);
  }
  return {c0 - reach, r0 - reach, c1 - c0 + 2 * reach + 1, r1 - r0 + 2 * reach + 1};
}

// The keypoints of the extrema `at` of one layer of octave `oc` (in the image's pixels, where `mask`
// allows them), one per dominant orientation, in row order, duplicates once.
std::vector<Oriented> oriented_keypoints(const std::vector<Extremum>& ext, const std::vector<int>& at, const Gradients& grad,
                                         const cv::Size& image, const cv::Mat& mask, const ScaleSpaceOptions& o, int oc) {
  std::vector<std::vector<Oriented>> per(at.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(at.size())), [&](const cv::Range& R) {
    for (int q = R.start; q < R.end; ++q) {
      const Extremum& e = ext[at[q]];
      const float scl = octave_scale(e, o);
      cv::KeyPoint kp;
      kp.pt = image_position(e, oc);
      const int mx = std::clamp(cvRound(kp.pt.x), 0, image.width - 1), my = std::clamp(cvRound(kp.pt.y), 0, image.height - 1);
      if (!mask.empty() && mask.at<uint8_t>(my, mx) == 0) continue;
      kp.size = 2 * scl * to_image(oc);
      kp.response = e.contrast;
      kp.octave = ((oc - 1) & 255) | (e.layer << 8) | (cvRound((e.xi + 0.5f) * 255) << 16);
      float peaks[kOriBins];
      const int n = orientations(grad, e.c, e.r, scl, peaks);
      for (int p = 0; p < n; ++p) {
        float angle = 360.f - peaks[p];
        if (std::abs(angle - 360.f) < FLT_EPSILON) angle = 0.f;
        kp.angle = angle;
        // the descriptor's orientation, as OpenCV derives it from the angle
        float ori = 360.f - angle;
        if (std::abs(ori - 360.f) < FLT_EPSILON) ori = 0.f;
        per[q].push_back({kp, e.c + e.xc, e.r + e.xr, scl, ori});
      }
    }
  });
  std::vector<Oriented> ks;
  for (auto& v : per) ks.insert(ks.end(), v.begin(), v.end());
  // duplicates (two samples interpolated to the same extremum) once
  std::vector<int> order(ks.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    const cv::KeyPoint &p = ks[a].kp, &q = ks[b].kp;
    if (p.pt.y != q.pt.y) return p.pt.y < q.pt.y;  // row order: neighbouring windows share cache lines
    if (p.pt.x != q.pt.x) return p.pt.x < q.pt.x;
    if (p.size != q.size) return p.size > q.size;
    return p.angle < q.angle;
  });
  std::vector<Oriented> out;
  for (int i : order)
    if (out.empty() || !same_keypoint(out.back().kp, ks[i].kp)) out.push_back(ks[i]);
  return out;
}

// Appends the keypoints `ks` and their descriptors (128 floats each) to `keypoints` and `desc`.
void describe(const std::vector<Oriented>& ks, const Gradients& grad, std::vector<cv::KeyPoint>& keypoints,
              std::vector<float>& desc) {
  const size_t first = keypoints.size();
  keypoints.resize(first + ks.size());
  desc.resize(keypoints.size() * 128);
  cv::parallel_for_(cv::Range(0, static_cast<int>(ks.size())), [&](const cv::Range& R) {
    for (int q = R.start; q < R.end; ++q) {
      const Oriented& s = ks[static_cast<size_t>(q)];
      keypoints[first + q] = s.kp;
      descriptor(grad, s.x, s.y, s.ori, s.scl, desc.data() + (first + q) * 128);
    }
  });
}
}  // namespace

void keep_strongest(const std::vector<cv::KeyPoint>& kp, std::vector<int>& idx, int n) {
  if (n <= 0 || static_cast<int>(idx.size()) <= n) return;
  std::stable_sort(idx.begin(), idx.end(), [&](int a, int b) { return kp[a].response > kp[b].response; });
  idx.resize(n);
  std::sort(idx.begin(), idx.end());
}

void detect_sift_scale_space(const cv::Mat& image, const cv::Mat& mask, const ScaleSpaceOptions& o,
                             std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
  if (image.type() != CV_8UC1) throw std::invalid_argument("detect_sift_scale_space: the image must be CV_8UC1");
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != image.size()))
    throw std::invalid_argument("detect_sift_scale_space: the mask must be CV_8UC1 of the image's size");
  if (o.octave_layers < 1) throw std::invalid_argument("detect_sift_scale_space: octave_layers must be at least 1");
  keypoints.clear();
  std::vector<float> desc;
  const int L = o.octave_layers;
  if (image.empty()) {
    descriptors.create(0, 128, CV_32F);
    return;
  }
  const std::vector<double> step = layer_steps(o);
  cv::Mat base = first_octave(image, o.sigma);
  const int octaves = std::max(1, cvRound(std::log2(static_cast<double>(std::min(base.cols, base.rows))) - 2) + 1);
  for (int oc = 0; oc < octaves; ++oc) {
    if (oc > 0) base = decimated(base);
    if (base.rows <= 2 * kBorder || base.cols <= 2 * kBorder) break;
    // the octave's Gaussian layers; the differences D[l] = G[l + 1] - G[l] are taken where they are read,
    // never stored (so the octave holds L + 3 planes at its peak, not 2 L + 5)
    std::vector<cv::Mat> G(L + 3);
    G[0] = base;
    base.release();
    const Window win = scan_window(o.region, oc, G[0].size());
    const std::vector<cv::Rect> need = layer_rects(win, G[0].size(), step);
    for (int i = 1; i < L + 3; ++i) G[i] = gaussian_blur(G[i - 1], step[i], need[i]);
    const std::vector<Extremum> ext = extrema(G, L, o, win);
    G[0].release();
    G[L + 1].release();
    G[L + 2].release();
    for (int l = 1; l <= L; ++l) {
      std::vector<int> at;  // the layer's extrema in the wanted region
      for (int e = 0; e < static_cast<int>(ext.size()); ++e) {
        const cv::Point2f p = image_position(ext[e], oc);
        if (ext[e].layer == l && o.region.contains(p.x, p.y)) at.push_back(e);
      }
      if (at.empty()) continue;
      const Gradients grad = gradients(G[l], window_box(ext, at, o));
      describe(oriented_keypoints(ext, at, grad, image.size(), mask, o, oc), grad, keypoints, desc);
    }
    base = G[L];
  }
  descriptors.create(static_cast<int>(keypoints.size()), 128, CV_32F);
  if (!keypoints.empty()) std::copy(desc.begin(), desc.end(), descriptors.ptr<float>(0));
}

}  // namespace tpkit
