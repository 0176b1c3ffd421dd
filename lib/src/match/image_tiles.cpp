#include "tpkit/match/image_tiles.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "tpkit/core/error.hpp"
#include "tpkit/core/parallel_for.hpp"

namespace tpkit {

// Luminance weights of R, G, B: ITU-R BT.601's luma, what OpenCV's cvtColor (COLOR_RGB2GRAY) gives.
// COLMAP 3.8 matches FreeImage's grey conversion, BT.709's 0.2126, 0.7152, 0.0722 (more green); on eight
// pairs of the WorldView-3 Jacksonville crops BT.601 found 11920 verified matches in all, BT.709 11839,
// band 1 alone 9248 and band 2 alone 11764: the weights matter little, using every band does.
constexpr float kLuma[3] = {0.299f, 0.587f, 0.114f};
constexpr const char* kLumaName = "luminance=0.299R+0.587G+0.114B";

void default_rendering(const ImageInfo& info, std::vector<float>& weights, std::string& rendering) {
  if (info.rgb && info.bands >= 3) {
    weights.assign(static_cast<size_t>(info.bands), 0.0f);
    std::copy(kLuma, kLuma + 3, weights.begin());
    rendering = kLumaName;
  } else if (info.bands > 1) {
    weights.assign(static_cast<size_t>(info.bands), 1.0f / static_cast<float>(info.bands));
    rendering = "mean=bands1-" + std::to_string(info.bands);
  } else {
    weights.assign(1, 1.0f);
    rendering = "band=1";
  }
}

ImageSource open_image_source(const std::string& path, std::optional<int> band, std::optional<double> nodata,
                              const std::string& mask) {
  ImageSource s;
  s.path = path;
  s.info = image_info(path);
  if (band && (*band < 0 || *band >= s.info.bands))
    throw InputError(path, 0, "band " + std::to_string(*band + 1) + " does not exist (the image has " +
                                  std::to_string(s.info.bands) + (s.info.bands == 1 ? " band)" : " bands)"));
  if (band) {
    s.weights.assign(static_cast<size_t>(*band) + 1, 0.0f);
    s.weights.back() = 1.0f;
    s.rendering = "band=" + std::to_string(*band + 1);
  } else {
    default_rendering(s.info, s.weights, s.rendering);
  }
  if (s.info.width <= 0 || s.info.height <= 0) throw InputError(path, 0, "empty image");
  s.nodata = nodata ? nodata : s.info.nodata;
  if (!mask.empty()) {
    ImageInfo mi = image_info(mask);
    if (mi.width != s.info.width || mi.height != s.info.height)
      throw InputError(mask, 0, "mask is " + std::to_string(mi.width) + "x" + std::to_string(mi.height) + " but the image " +
                                    path + " is " + std::to_string(s.info.width) + "x" + std::to_string(s.info.height));
    s.mask = mask;
  }
  return s;
}

Raster read_valid_region(const ImageSource& src, long x0, long y0, long w, long h, Raster reuse) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const double nd = src.nodata ? *src.nodata : 0;
  auto nodata = [&](float v) { return src.nodata && (v == static_cast<float>(nd) || (std::isnan(nd) && std::isnan(v))); };
  // the bands of the rendering read together (a TIFF that interleaves them decoded once) and summed into
  // the first (a single band's weight of 1 leaves its values exact), a pixel nodata in any of them NaN
  std::vector<int> bands;
  std::vector<float> weights;
  for (size_t k = 0; k < src.weights.size(); ++k)
    if (src.weights[k] != 0) bands.push_back(static_cast<int>(k)), weights.push_back(src.weights[k]);
  std::vector<Raster> b = read_region_bands(src.path, bands, x0, y0, w, h, std::move(reuse));
  Raster& r = b.front();
  for (float& v : r.data) v = nodata(v) ? nan : weights[0] * v;
  for (size_t j = 1; j < b.size(); ++j) {
    const float wj = weights[j];
    for (size_t i = 0; i < r.data.size(); ++i) r.data[i] = nodata(b[j].data[i]) ? nan : r.data[i] + wj * b[j].data[i];
  }
  if (!src.mask.empty() && !r.data.empty()) {
    Raster m = read_region(src.mask, 0, r.x0, r.y0, r.width, r.height);
    for (size_t i = 0; i < r.data.size(); ++i)
      if (!(m.data[i] != 0)) r.data[i] = nan;
  }
  for (float& v : r.data)
    if (!std::isfinite(v)) v = nan;
  return std::move(r);  // b's first raster
}

long stretch_step(long width, long height, long max_samples) {
  long k = 1;
  while ((width / k) * (height / k) > max_samples) ++k;
  return k;
}

void add_stretch_samples(const Raster& strip, long step, std::vector<float>& samples) {
  for (long yy = 0; yy < strip.height; ++yy) {
    if ((strip.y0 + yy) % step) continue;
    for (long x = 0; x < strip.width; x += step) {
      float v = strip.at(x, yy);
      if (!std::isnan(v)) samples.push_back(v);
    }
  }
}

Stretch stretch_of_samples(std::vector<float> samples, double p_lo, double p_hi, const ImageSource& src) {
  if (samples.empty()) {
    std::string what = src.rendering;  // "band 2", "luminance 0.299R+0.587G+0.114B"
    what[what.find('=')] = ' ';
    throw InputError(src.path, 0, "every pixel of " + what + " is nodata or masked");
  }
  Stretch s;
  s.valid_samples = static_cast<long>(samples.size());
  // the order of the samples does not matter: nth_element gives the value of rank i
  auto at = [&](double p) {
    size_t i = static_cast<size_t>(std::llround(p / 100.0 * static_cast<double>(samples.size() - 1)));
    i = std::min(i, samples.size() - 1);
    std::nth_element(samples.begin(), samples.begin() + static_cast<long>(i), samples.end());
    return static_cast<double>(samples[i]);
  };
  s.lo = at(p_lo);
  s.hi = at(p_hi);
  return s;
}

Stretch percentile_stretch(const ImageSource& src, double p_lo, double p_hi, long max_samples, int threads) {
  const long W = src.info.width, H = src.info.height;
  const long k = stretch_step(W, H, max_samples);
  // strips of ~4 M pixels (a multiple of k rows), read side by side on `threads` workers (decoding a
  // compressed file is most of the time: 1.1 s for a 10000² deflate image on one thread), their samples
  // gathered in row order
  const long strip = std::max(k, (k * std::max(1L, (1L << 22) / std::max(1L, W)) / k));
  const size_t strips = static_cast<size_t>((H + strip - 1) / strip);
  std::vector<std::vector<float>> per(strips);
  parallel_for(strips, std::max(1, std::min(threads, 4)), [&](size_t i) {
    const long y = static_cast<long>(i) * strip, h = std::min(strip, H - y);
    add_stretch_samples(read_valid_region(src, 0, y, W, h), k, per[i]);
  });
  std::vector<float> samples;
  size_t n = 0;
  for (const auto& p : per) n += p.size();
  samples.reserve(n);
  for (auto& p : per) {
    samples.insert(samples.end(), p.begin(), p.end());
    std::vector<float>().swap(p);
  }
  return stretch_of_samples(std::move(samples), p_lo, p_hi, src);
}

std::vector<uint8_t> render_u8(const Raster& r, const Stretch& s, std::vector<uint8_t>* valid) {
  return render_u8(r, r.x0, r.y0, r.width, r.height, s, valid);
}

std::vector<uint8_t> render_u8(const Raster& r, long x0, long y0, long w, long h, const Stretch& s, std::vector<uint8_t>* valid) {
  if (x0 < r.x0 || y0 < r.y0 || w < 0 || h < 0 || x0 + w > r.x0 + r.width || y0 + h > r.y0 + r.height)
    throw std::invalid_argument("render_u8: the window must lie within the raster");
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  std::vector<uint8_t> out(n);
  if (valid) valid->resize(n);
  const double span = s.hi - s.lo;
  const double g = span > 0 ? 255.0 / span : 0.0;
  // rows side by side on OpenCV's pool: a detection tile's 1.5 million pixels took 4 ms on one thread
  // while the other waited (0.8 s of a 10000² pair's detection, with the crop this replaces)
  cv::parallel_for_(cv::Range(0, static_cast<int>(h)), [&](const cv::Range& rows) {
    for (long y = rows.start; y < rows.end; ++y) {
      const float* in = r.data.data() + static_cast<size_t>(y0 - r.y0 + y) * static_cast<size_t>(r.width) + static_cast<size_t>(x0 - r.x0);
      uint8_t* o = out.data() + static_cast<size_t>(y) * static_cast<size_t>(w);
      // the grey level rounded half up (x + 0.5 truncated: std::round's value for x >= 0; below 0 the
      // clamp gives 0 either way), NaN 0: a loop the compiler vectorises
      for (long i = 0; i < w; ++i) {
        const double x = (static_cast<double>(in[i]) - s.lo) * g;
        o[i] = x > 0 ? static_cast<uint8_t>(std::min(x, 255.0) + 0.5) : 0;  // NaN: x > 0 is false
      }
      if (valid) {
        uint8_t* v = valid->data() + static_cast<size_t>(y) * static_cast<size_t>(w);
        for (long i = 0; i < w; ++i) v[i] = std::isnan(in[i]) ? 0 : 255;
      }
    }
  }, std::max(1.0, static_cast<double>(h) / 64));
  return out;
}

std::vector<Tile> tile_grid(long width, long height, long tile, long overlap) {
  if (tile <= 0) tile = std::max(width, height);
  std::vector<Tile> tiles;
  // even split into cores of nearly equal size, at most about 1.5 tile on a side
  long nx = std::max(1L, (2 * width + tile) / (2 * tile)), ny = std::max(1L, (2 * height + tile) / (2 * tile));
  for (long j = 0; j < ny; ++j)
    for (long i = 0; i < nx; ++i) {
      Tile t;
      t.index = static_cast<int>(tiles.size());
      t.cx0 = width * i / nx;
      t.cx1 = width * (i + 1) / nx;
      t.cy0 = height * j / ny;
      t.cy1 = height * (j + 1) / ny;
      t.rx0 = std::max(0L, t.cx0 - overlap);
      t.ry0 = std::max(0L, t.cy0 - overlap);
      t.rx1 = std::min(width, t.cx1 + overlap);
      t.ry1 = std::min(height, t.cy1 + overlap);
      tiles.push_back(t);
    }
  return tiles;
}

}  // namespace tpkit
