#include "tpkit/ortho/ortho_alignment.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <cmath>
#include <mutex>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/core/text_table.hpp"

namespace tpkit {

namespace {
double median_of(std::vector<double> v) {
  if (v.empty()) return NAN;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(m), v.end());
  const double hi = v[m];
  if (v.size() % 2) return hi;
  return (hi + *std::max_element(v.begin(), v.begin() + static_cast<long>(m))) / 2;
}

double nmad_of(const std::vector<double>& v, double med) {
  std::vector<double> d;
  for (double x : v) d.push_back(std::abs(x - med));
  return 1.4826 * median_of(d);
}

bool same_grid(const OrthoGrid& a, const OrthoGrid& b) {
  const double tol = 1e-6 * a.gsd;
  return a.epsg == b.epsg && std::abs(a.gsd - b.gsd) <= 1e-9 * a.gsd && std::abs(a.x0 - b.x0) <= tol && std::abs(a.y0 - b.y0) <= tol &&
         a.width == b.width && a.height == b.height;
}

// The mean of the first three bands of the region, NaN where any is nodata.
GreyTile read_grey(const std::string& path, const OrthoFileInfo& info, long x0, long y0, long w, long h) {
  const int n = std::min(3, info.bands);
  std::vector<int> bands;
  for (int b = 0; b < n; ++b) bands.push_back(b);
  const std::vector<Raster> r = read_region_bands(path, bands, x0, y0, w, h);
  GreyTile g;
  g.width = r[0].width;
  g.height = r[0].height;
  g.data.assign(r[0].data.size(), 0.0f);
  for (const Raster& band : r)
    for (size_t i = 0; i < g.data.size(); ++i) {
      const float v = band.data[i];
      const bool bad = std::isnan(v) || (info.has_nodata && v == static_cast<float>(info.nodata));
      g.data[i] = bad || std::isnan(g.data[i]) ? NAN : g.data[i] + v / n;
    }
  return g;
}
}  // namespace

bool measure_tile_shift(const GreyTile& a, const GreyTile& b, const AlignmentOptions& o, TileShift& out) {
  const int w = static_cast<int>(a.width), h = static_cast<int>(a.height);
  cv::Mat A(h, w, CV_32F), Bm(h, w, CV_32F), mask(h, w, CV_8U);
  long valid = 0;
  double sa = 0, sb = 0;
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const size_t i = static_cast<size_t>(r) * w + c;
      const bool ok = std::isfinite(a.data[i]) && std::isfinite(b.data[i]);
      mask.at<uint8_t>(r, c) = ok ? 255 : 0;
      if (ok) {
        ++valid;
        sa += a.data[i];
        sb += b.data[i];
      }
    }
  if (valid < o.min_valid * w * h || valid < 16) return false;
  // invalid pixels take the mean of the valid ones (they are few: a tile needs min_valid of its pixels)
  const float ma = static_cast<float>(sa / valid), mb = static_cast<float>(sb / valid);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const size_t i = static_cast<size_t>(r) * w + c;
      const bool ok = mask.at<uint8_t>(r, c) != 0;
      A.at<float>(r, c) = ok ? a.data[i] : ma;
      Bm.at<float>(r, c) = ok ? b.data[i] : mb;
    }
  cv::Scalar mean, sd;
  cv::meanStdDev(A, mean, sd, mask);
  if (!(sd[0] > 1e-3 * std::max(1.0, std::abs(mean[0])))) return false;  // no texture
  cv::meanStdDev(Bm, mean, sd, mask);
  if (!(sd[0] > 1e-3 * std::max(1.0, std::abs(mean[0])))) return false;
  // whole pixels: phase correlation (Hann window); B(x) = A(x - d) gives d
  cv::Mat hann;
  cv::createHanningWindow(hann, A.size(), CV_32F);
  // (on copies: at an optimal DFT size OpenCV multiplies the window into its inputs in place)
  const cv::Point2d d0 = cv::phaseCorrelate(A.clone(), Bm.clone(), hann);
  // refined: ECC, translation; the warp maps A's pixel x to B's x + t. 100 iterations whatever the change of
  // the correlation: on smooth real content it creeps (a stop at a change of 1e-6 left a tenth of the shift,
  // on the Marseille orthos of tests/tools/tp-ortho.cmake); 60 were 0.02 px short there, 300 no better than 100
  cv::Mat warp = (cv::Mat_<float>(2, 3) << 1, 0, static_cast<float>(d0.x), 0, 1, static_cast<float>(d0.y));
  double ecc = 0;
  try {
    ecc = cv::findTransformECC(A, Bm, warp, cv::MOTION_TRANSLATION,
                               cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12), mask, 1);
  } catch (const cv::Exception&) {
    return false;
  }
  if (!(ecc >= o.min_ecc)) return false;
  out.dx = warp.at<float>(0, 2);
  out.dy = warp.at<float>(1, 2);
  out.ecc = ecc;
  // ECC ran off to another optimum: more than a quarter of the tile from where the phase correlation's peak put it
  if (std::hypot(out.dx - d0.x, out.dy - d0.y) > std::min(w, h) / 4.0) return false;
  return std::isfinite(out.dx) && std::isfinite(out.dy);
}

PairAlignment measure_alignment(const std::string& a, const std::string& b, const AlignmentOptions& o) {
  const OrthoFileInfo ia = read_ortho_info(a), ib = read_ortho_info(b);
  if (!same_grid(ia.grid, ib.grid))
    throw InputError(b, 0, "not on the grid of " + a + " (EPSG, corner, pixel size and size must agree: make both with one tp-ortho run, or --like)");
  const OrthoGrid& g = ia.grid;
  const long T = o.tile, across = g.width / T, down = g.height / T;
  PairAlignment res;
  std::mutex m;
  parallel_for(static_cast<size_t>(std::max(0L, across * down)), o.threads, [&](size_t k) {
    const long x0 = (static_cast<long>(k) % across) * T + (g.width - across * T) / 2;
    const long y0 = (static_cast<long>(k) / across) * T + (g.height - down * T) / 2;
    const GreyTile ta = read_grey(a, ia, x0, y0, T, T), tb = read_grey(b, ib, x0, y0, T, T);
    long both = 0;
    for (size_t i = 0; i < ta.data.size(); ++i) both += std::isfinite(ta.data[i]) && std::isfinite(tb.data[i]);
    if (both < o.min_valid * T * T) return;
    TileShift s;
    const bool ok = measure_tile_shift(ta, tb, o, s);
    std::lock_guard<std::mutex> lock(m);
    ++res.tiles_tried;
    if (!ok) return;
    s.x = x0 + (T - 1) / 2.0;
    s.y = y0 + (T - 1) / 2.0;
    res.tiles.push_back(s);
  });
  std::sort(res.tiles.begin(), res.tiles.end(), [](const TileShift& p, const TileShift& q) { return p.y != q.y ? p.y < q.y : p.x < q.x; });
  std::vector<double> dx, dy;
  for (const auto& t : res.tiles) {
    dx.push_back(t.dx);
    dy.push_back(t.dy);
  }
  res.dx = median_of(dx);
  res.dy = median_of(dy);
  res.nmad_dx = nmad_of(dx, res.dx);
  res.nmad_dy = nmad_of(dy, res.dy);
  return res;
}

}  // namespace tpkit
