#include "tpkit/match/pair_geometry.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "tpkit/match/affine_fundamental.hpp"
#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/match/match_descriptors.hpp"
#include "tpkit/match/root_sift.hpp"
#include "tpkit/match/sift_scale_space.hpp"
#include "tpkit/core/text_table.hpp"

namespace tpkit {

namespace {

// The image averaged in f x f blocks (see the header), read in strips of whole blocks; on the way, the
// samples of its percentile stretch (image_tiles.hpp: every `step`-th pixel of every step-th row, the
// rows past the last whole block included), so that the image is decoded once for both.
Raster decimated(const ImageSource& src, long f, long step, std::vector<float>& stretch_samples) {
  const long W = src.info.width, H = src.info.height;
  Raster out;
  out.width = std::max(1L, W / f);
  out.height = std::max(1L, H / f);
  out.data.assign(static_cast<size_t>(out.width) * out.height, 0.f);
  const long blocks_per_strip = std::max(1L, (1L << 22) / std::max(1L, W * f));
  for (long by = 0; by < out.height; by += blocks_per_strip) {
    const long nb = std::min(blocks_per_strip, out.height - by);
    const Raster r = read_valid_region(src, 0, by * f, W, nb * f);
    add_stretch_samples(r, step, stretch_samples);
    for (long j = 0; j < nb; ++j)
      for (long i = 0; i < out.width; ++i) {
        double s = 0;
        for (long y = j * f; y < std::min(r.height, (j + 1) * f); ++y)
          for (long x = i * f; x < std::min(r.width, (i + 1) * f); ++x) s += r.at(x, y);  // NaN spreads
        out.at(i, by + j) = static_cast<float>(s / static_cast<double>(f * f));
      }
  }
  if (out.height * f < H) add_stretch_samples(read_valid_region(src, 0, out.height * f, W, H - out.height * f), step, stretch_samples);
  return out;
}

struct CoarseFeatures {
  std::vector<cv::KeyPoint> kp;  // full-resolution pixels
  cv::Mat desc;
};

// `r`: the image decimated by f.
CoarseFeatures coarse_features(const Raster& r, const SiftOptions& o, const PairGeometryOptions& g, const Stretch& st, long f) {
  std::vector<uint8_t> valid;
  std::vector<uint8_t> u8 = render_u8(r, st, &valid);
  cv::Mat img(static_cast<int>(r.height), static_cast<int>(r.width), CV_8U, u8.data());
  cv::Mat mask(static_cast<int>(r.height), static_cast<int>(r.width), CV_8U, valid.data());
  cv::Mat eroded;
  cv::erode(mask, eroded, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(9, 9)));
  CoarseFeatures out;
  cv::Mat desc;
  detect_sift_scale_space(img, eroded, scale_space_options(o), out.kp, desc);
  std::vector<int> keep(out.kp.size());
  std::iota(keep.begin(), keep.end(), 0);
  keep_strongest(out.kp, keep, g.max_keypoints);
  std::vector<cv::KeyPoint> kept;
  out.desc.create(static_cast<int>(keep.size()), 128, CV_8U);
  for (size_t j = 0; j < keep.size(); ++j) {
    kept.push_back(out.kp[keep[j]]);
    root_sift_row(desc, keep[j], out.desc.ptr<uint8_t>(static_cast<int>(j)));
  }
  out.kp = std::move(kept);
  const double c = (static_cast<double>(f) - 1) / 2;
  for (auto& k : out.kp) {
    k.pt.x = static_cast<float>(f * k.pt.x + c);
    k.pt.y = static_cast<float>(f * k.pt.y + c);
  }
  return out;
}

long decimation(const ImageSource& s, long max_side) {
  const long side = std::max(s.info.width, s.info.height);
  return std::max(1L, (side + max_side - 1) / std::max(1L, max_side));
}

}  // namespace

PairGeometry estimate_pair_geometry(const ImageSource& a, const ImageSource& b, const SiftOptions& sift,
                                    const PairGeometryOptions& g) {
  PairGeometry G;
  G.image1 = {a.path, a.info.width, a.info.height};
  G.image2 = {b.path, b.info.width, b.info.height};
  G.detector1 = detector_tag(sift, a);
  G.detector2 = detector_tag(sift, b);
  G.scale1 = decimation(a, g.max_side);
  G.scale2 = decimation(b, g.max_side);
  // each image decoded once: its decimated copy and the samples of its stretch (as percentile_stretch's)
  auto features = [&](const ImageSource& s, long f, Stretch& st) {
    std::vector<float> samples;
    const Raster r = decimated(s, f, stretch_step(s.info.width, s.info.height), samples);
    st = stretch_of_samples(std::move(samples), sift.stretch_lo, sift.stretch_hi, s);
    return coarse_features(r, sift, g, st, f);
  };
  const CoarseFeatures f1 = features(a, G.scale1, G.stretch1);
  const CoarseFeatures f2 = features(b, G.scale2, G.stretch2);
  DescriptorMatchOptions dm;
  dm.exact_below = std::numeric_limits<long>::max();
  const std::vector<DescriptorMatch> put =
      f1.kp.empty() || f2.kp.empty() ? std::vector<DescriptorMatch>{} : match_descriptors(f1.desc, f2.desc, dm);
  G.coarse_matches = static_cast<long>(put.size());
  const std::string what = a.path + " and " + b.path;
  if (G.coarse_matches < std::max(g.min_inliers, AffineFundamental::MINIMUM_SAMPLES))
    throw InputError(what + ": no coarse geometry (" + std::to_string(G.coarse_matches) +
                     " matches of the decimated images): do they overlap?");
  Eigen::MatrixX4d xy(put.size(), 4);
  for (size_t k = 0; k < put.size(); ++k) {
    const auto &p = f1.kp[put[k].i1].pt, &q = f2.kp[put[k].i2].pt;
    xy.row(static_cast<Eigen::Index>(k)) << p.x, p.y, q.x, q.y;
  }
  AffineFundamentalRansac ro;
  ro.threshold = g.ransac_threshold * static_cast<double>(std::max(G.scale1, G.scale2));
  ro.seed = g.seed;
  const AffineFundamentalResult rr = ransac_affine_fundamental(xy, ro);
  G.inliers = rr.ok ? rr.inliers : 0;
  if (G.inliers < g.min_inliers)
    throw InputError(what + ": no coarse geometry (" + std::to_string(G.inliers) + " affine F inliers of " +
                     std::to_string(G.coarse_matches) + " matches of the decimated images): do they overlap?");
  // least-squares 2-D affine map over the inliers, then the largest distance from it
  Eigen::MatrixX3d M(G.inliers, 3);
  Eigen::MatrixX2d T(G.inliers, 2);
  Eigen::Index q = 0;
  for (Eigen::Index k = 0; k < xy.rows(); ++k)
    if (rr.inlier[static_cast<size_t>(k)]) {
      M.row(q) << xy(k, 0), xy(k, 1), 1.0;
      T.row(q) << xy(k, 2), xy(k, 3);
      ++q;
    }
  const Eigen::Matrix<double, 3, 2> X = M.colPivHouseholderQr().solve(T);
  G.A = X.transpose();
  const Eigen::MatrixX2d res = T - M * X;
  G.spread = res.rowwise().norm().maxCoeff();
  return G;
}

void save_pair_geometry(const std::string& path, const PairGeometry& G) {
  AtomicOutput out(path);
  Meta meta;
  meta_set(meta, "detector1", G.detector1);
  meta_set(meta, "detector2", G.detector2);
  meta_set(meta, "coarse", std::to_string(G.inliers) + " affine F inliers of " + std::to_string(G.coarse_matches) +
                               " SIFT matches of the images decimated by " + std::to_string(G.scale1) + " and " +
                               std::to_string(G.scale2));
  meta_set(meta, "map", "x2 = a11 x1 + a12 y1 + a13, y2 = a21 x1 + a22 y1 + a23 (pixels); spread: largest distance of an inlier from it");
  write_header(out.stream(), "geometry", 1, {G.image1, G.image2}, meta,
               {"a11", "a12", "a13", "a21", "a22", "a23", "spread", "lo1", "hi1", "lo2", "hi2"});
  write_record(out.stream(), {G.A(0, 0), G.A(0, 1), G.A(0, 2), G.A(1, 0), G.A(1, 1), G.A(1, 2), G.spread, G.stretch1.lo,
                              G.stretch1.hi, G.stretch2.lo, G.stretch2.hi});
  out.commit();
}

PairGeometry read_pair_geometry(const std::string& path) {
  ReadOptions ro;
  ro.kind = "geometry";
  ro.default_columns = [](size_t) { return std::vector<std::string>{}; };
  const TextTable t = read_table_file(path, ro);
  if (t.kind != "geometry") throw InputError(path, 0, "not a tpkit geometry file (no '# tpkit geometry 1' line)");
  if (t.images.size() != 2) throw InputError(path, 0, "a geometry file names two images (image1, image2)");
  if (t.rows.size() != 1) throw InputError(path, 0, "a geometry file holds one record, found " + std::to_string(t.rows.size()));
  PairGeometry G;
  G.image1 = t.images[0];
  G.image2 = t.images[1];
  G.detector1 = meta_get(t.meta, "detector1");
  G.detector2 = meta_get(t.meta, "detector2");
  const auto& r = t.rows[0];
  auto v = [&](const char* name) { return r[static_cast<size_t>(t.require(name))]; };
  G.A << v("a11"), v("a12"), v("a13"), v("a21"), v("a22"), v("a23");
  G.spread = v("spread");
  G.stretch1 = {v("lo1"), v("hi1"), 0};
  G.stretch2 = {v("lo2"), v("hi2"), 0};
  const long line = t.row_line.empty() ? 0 : t.row_line[0];
  if (!G.A.allFinite() || !std::isfinite(G.spread) || G.spread < 0)
    throw InputError(path, line, "the map and the spread must be finite, the spread >= 0");
  if (!(G.stretch1.lo <= G.stretch1.hi) || !(G.stretch2.lo <= G.stretch2.hi))
    throw InputError(path, line, "a stretch needs lo <= hi");
  // the map of one view onto another of the same ground: its linear part shrinks no direction to
  // nothing (a region's image-2 window would be a line or a point, and its matches silently lost). No
  // two views that tp-match matches differ by a factor 1000 in scale.
  const Eigen::Vector2d sv = G.A.leftCols<2>().jacobiSvd().singularValues();
  if (!(sv(1) >= 1e-3 * std::max(1.0, sv(0))))
    throw InputError(path, line, "the map a11 .. a22 is singular or nearly (singular values " + format_number(sv(0)) + " and " +
                                     format_number(sv(1)) + "): not a map between two views of one scene");
  return G;
}

void check_pair_geometry(const PairGeometry& G, const std::string& path, const ImageSource& a, const ImageSource& b,
                         const SiftOptions& sift) {
  auto same = [&](const ImageRef& r, const ImageSource& s, const char* which) {
    if (r.width != s.info.width || r.height != s.info.height)
      throw InputError(path, 0, std::string(which) + " is " + std::to_string(r.width) + "x" + std::to_string(r.height) +
                                    " in the geometry but " + s.path + " is " + std::to_string(s.info.width) + "x" +
                                    std::to_string(s.info.height) + ": a geometry of another pair?");
  };
  // the images it names: the same path, or another path to the same file (a size alone would let the
  // geometry of any two images of the same sizes through)
  auto is = [](const ImageRef& r, const ImageSource& s) {
    if (r.path == s.path) return true;
    std::error_code ec;
    return std::filesystem::equivalent(r.path, s.path, ec) && !ec;
  };
  if (!is(G.image1, a) || !is(G.image2, b))
    throw InputError(path, 0, "a geometry of " + G.image1.path + " and " + G.image2.path + ", not of " + a.path + " and " +
                                  b.path + " (made by tp-match --write-geometry for those images)");
  same(G.image1, a, "image1");
  same(G.image2, b, "image2");
  if (G.detector1 != detector_tag(sift, a) || G.detector2 != detector_tag(sift, b))
    throw InputError(path, 0, "made with other detector options (detector1/detector2 differ from this run's: " +
                                  detector_tag(sift, a) + ")");
}

std::array<double, 4> image2_window(const PairGeometry& G, const std::array<double, 4>& w, double margin) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (double x : {w[0], w[2]})
    for (double y : {w[1], w[3]}) {
      const double u = G.A(0, 0) * x + G.A(0, 1) * y + G.A(0, 2), v = G.A(1, 0) * x + G.A(1, 1) * y + G.A(1, 2);
      x0 = std::min(x0, u), x1 = std::max(x1, u), y0 = std::min(y0, v), y1 = std::max(y1, v);
    }
  const double m = G.spread + margin;
  return {x0 - m, y0 - m, x1 + m, y1 + m};
}

}  // namespace tpkit
