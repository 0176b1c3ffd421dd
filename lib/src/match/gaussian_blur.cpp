#include "tpkit/match/gaussian_blur.hpp"

#include <algorithm>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "tpkit/core/cpu_dispatch.hpp"

namespace tpkit {

namespace {
// N bytes of floats (GCC's vector extension): 16 in the baseline code, 32 in the AVX2 code; loaded and
// stored unaligned.
template <int N>
struct Lanes {
  typedef float type __attribute__((vector_size(N)));
};

// The templates below are always inlined into their callers (the AVX2 one for 32-byte vectors): a
// vector never crosses a call, so GCC's note that passing one without AVX changes the ABI does not apply.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

template <class V>
[[gnu::always_inline]] inline V load(const float* p) {
  V v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

template <class V>
[[gnu::always_inline]] inline void store(float* p, const V& v) {
  std::memcpy(p, &v, sizeof v);
}

// out[x] = k[0] up[0][x] + sum over i = 1..r of k[i] (up[i][x] + down[i][x]), x in [0, n): a pass of the
// symmetric kernel, up[i] and down[i] the samples at distance i on either side (the column pass: source
// rows i above and below; the row pass: the row buffer shifted by -i and +i). Four vectors of output at
// a time, so that four sums go on side by side; the pixels past the last whole block one by one, in the
// same order of operations as a lane.
template <int N>
[[gnu::always_inline]] inline void symmetric_pass(const float* const* up, const float* const* down, const float* k, int r, int n,
                                                  float* out) {
  using V = typename Lanes<N>::type;
  constexpr int W = N / 4, B = 4 * W;
  int x = 0;
  for (; x + B <= n; x += B) {
    const float* s = up[0] + x;
    V a0 = k[0] * load<V>(s), a1 = k[0] * load<V>(s + W), a2 = k[0] * load<V>(s + 2 * W), a3 = k[0] * load<V>(s + 3 * W);
    for (int i = 1; i <= r; ++i) {
      const float ki = k[i], *u = up[i] + x, *d = down[i] + x;
      a0 += ki * (load<V>(u) + load<V>(d));
      a1 += ki * (load<V>(u + W) + load<V>(d + W));
      a2 += ki * (load<V>(u + 2 * W) + load<V>(d + 2 * W));
      a3 += ki * (load<V>(u + 3 * W) + load<V>(d + 3 * W));
    }
    store(out + x, a0);
    store(out + x + W, a1);
    store(out + x + 2 * W, a2);
    store(out + x + 3 * W, a3);
  }
  for (; x < n; ++x) {
    float a = k[0] * up[0][x];
    for (int i = 1; i <= r; ++i) a += k[i] * (up[i][x] + down[i][x]);
    out[x] = a;
  }
}

// Output rows [a, b), columns [x0, x1) of the blur: the column pass of each into `col` (cols + 2 r floats)
// over the columns the row pass reads, the row buffer's borders filled by reflection where it reaches
// them, then the row pass. A pixel's value does not depend on the columns computed with it.
template <int N>
[[gnu::always_inline]] inline void blur_rows(const cv::Mat& src, const std::vector<float>& k, const std::vector<int>& border, int a,
                                             int b, int x0, int x1, float* col, cv::Mat& dst) {
  const int rows = src.rows, cols = src.cols, r = static_cast<int>(k.size()) - 1;
  const int ca = std::max(0, x0 - r), cb = std::min(cols, x1 + r);  // the row buffer's computed columns
  std::vector<const float*> up(r + 1), down(r + 1), left(r + 1), right(r + 1);
  float* const c = col + r;  // c[x] for x in [-r, cols + r)
  for (int i = 0; i <= r; ++i) left[i] = c + x0 - i, right[i] = c + x0 + i;
  for (int y = a; y < b; ++y) {
    if (y + r + 2 < rows) prefetch_floats(src.ptr<float>(y + r + 2) + ca, cb - ca);  // the row the row after next brings in
    for (int i = 0; i <= r; ++i) {
      up[i] = src.ptr<float>(cv::borderInterpolate(y - i, rows, cv::BORDER_REFLECT_101)) + ca;
      down[i] = src.ptr<float>(cv::borderInterpolate(y + i, rows, cv::BORDER_REFLECT_101)) + ca;
    }
    symmetric_pass<N>(up.data(), down.data(), k.data(), r, cb - ca, c + ca);
    for (int j = 0; j < r; ++j) {
      if (x0 - r < 0) c[-1 - j] = c[border[j]];
      if (x1 + r > cols) c[cols + j] = c[border[r + j]];
    }
    symmetric_pass<N>(left.data(), right.data(), k.data(), r, x1 - x0, dst.ptr<float>(y) + x0);
  }
}

#pragma GCC diagnostic pop

#if TPKIT_HAS_AVX2
TPKIT_AVX2 void blur_rows_avx2(const cv::Mat& src, const std::vector<float>& k, const std::vector<int>& border, int a, int b,
                               int x0, int x1, float* col, cv::Mat& dst) {
  blur_rows<32>(src, k, border, a, b, x0, x1, col, dst);
}
#endif
}  // namespace

int gaussian_blur_radius(double sigma) { return (cvRound(sigma * 8 + 1) | 1) / 2; }  // OpenCV's size for floats (4 sigma each side)

cv::Mat gaussian_blur(const cv::Mat& src, double sigma, bool baseline) {
  return gaussian_blur(src, sigma, cv::Rect(0, 0, src.cols, src.rows), baseline);
}

cv::Mat gaussian_blur(const cv::Mat& src, double sigma, const cv::Rect& roi, bool baseline) {
  if (src.type() != CV_32F) throw std::invalid_argument("gaussian_blur: the plane must be CV_32F");
  if (!(sigma > 0)) throw std::invalid_argument("gaussian_blur: sigma must be > 0");
  cv::Mat dst(src.size(), CV_32F);
  const cv::Rect in = roi & cv::Rect(0, 0, src.cols, src.rows);
  if (in.empty()) return dst;
  const int cols = src.cols, r = gaussian_blur_radius(sigma);
  const cv::Mat kernel = cv::getGaussianKernel(2 * r + 1, sigma, CV_32F);
  std::vector<float> k(r + 1);  // k[i]: the weight at distance i
  for (int i = 0; i <= r; ++i) k[i] = kernel.at<float>(r + i);
  // the columns that the border entries -1 .. -r and cols .. cols + r - 1 reflect
  std::vector<int> border(2 * static_cast<size_t>(r));
  for (int j = 0; j < r; ++j) {
    border[j] = cv::borderInterpolate(-1 - j, cols, cv::BORDER_REFLECT_101);
    border[r + j] = cv::borderInterpolate(cols + j, cols, cv::BORDER_REFLECT_101);
  }
  const bool avx2 = cpu_has_avx2() && !baseline;
  // at most 64 strips of 32 rows or more, fixed by the size (the values do not depend on them)
  const int strips = std::max(1, std::min(64, in.height / 32));
  cv::parallel_for_(cv::Range(0, strips), [&](const cv::Range& R) {
    std::vector<float> col(static_cast<size_t>(cols) + 2 * r);
    for (int s = R.start; s < R.end; ++s) {
      const int a = in.y + static_cast<int>(static_cast<long>(in.height) * s / strips);
      const int b = in.y + static_cast<int>(static_cast<long>(in.height) * (s + 1) / strips);
#if TPKIT_HAS_AVX2
      if (avx2) {
        blur_rows_avx2(src, k, border, a, b, in.x, in.x + in.width, col.data(), dst);
        continue;
      }
#endif
      blur_rows<16>(src, k, border, a, b, in.x, in.x + in.width, col.data(), dst);
    }
  });
  (void)avx2;
  return dst;
}

}  // namespace tpkit
