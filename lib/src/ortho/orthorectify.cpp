#include "tpkit/ortho/orthorectify.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/ground/reference_dem.hpp"
#include "tpkit/ortho/occlusion.hpp"

namespace tpkit {

Resampling parse_resampling(const std::string& s) {
  if (s == "bilinear") return Resampling::bilinear;
  if (s == "bicubic") return Resampling::bicubic;
  throw UsageError("--resampling '" + s + "': bilinear or bicubic");
}

namespace {
constexpr long kTile = OrthoTiffLayout::kTile;
constexpr long kLattice = 16;             // exact ground points every 16 pixels of a tile
constexpr double kLatticeTolerance = 1e-3;  // pixels: a flat height's projection bilinear within a lattice cell
constexpr double kFoldBack = 3;           // normalized |lon|, |lat| beyond which the model is not trusted
constexpr double kMaxWindowPixels = 1 << 26;  // the image window one tile may read (64 Mpx): a guard
constexpr long kMaxOccluderMargin = 512;      // pixels: how far towards the sensor a tile looks for occluders

// What every tile needs.
struct Job {
  const std::string& image;
  const RpcModel& model;
  const OrthoGrid& grid;
  const GridCrs& crs;
  const OrthoSurface& surface;
  Resampling resampling;
  long width, height;  // the image's
  int bands;
  bool src_has_nodata;
  double src_nodata;
  SampleType type;
  double nodata;  // output
  double top = NAN;  // the surface's highest height over the grid (hidden ground only)
};

// A worker's buffers, kept from tile to tile: fresh ones cost a page fault and the zeroing of every page
// (a third of the run's time, measured on a Marseille crop).
struct Scratch {
  std::vector<double> sx, sy, lon, lat, h, lx, ly, nx, ny;
  std::vector<char> smooth, hidden;
  std::vector<unsigned char> samples;
  Raster reuse;
};

// The ground points (lon, lat) of grid pixels (c0 + i, r0 + j), i < w, j < h, row-major in lon, lat: exact
// (PROJ) on a lattice every kLattice pixels, whose nodes ((h - 1) / kLattice + 2 rows of (w - 1) / kLattice + 2)
// are left in lx, ly, and bilinear between them (a map projection is smooth: below 1e-6 m over 16 pixels).
void grid_lonlat(const Job& j, long c0, long r0, long w, long h, std::vector<double>& lx, std::vector<double>& ly, std::vector<double>& lon,
                 std::vector<double>& lat) {
  const OrthoGrid& g = j.grid;
  const long na = (h - 1) / kLattice + 2, nb = (w - 1) / kLattice + 2;
  lx.resize(static_cast<size_t>(na * nb));
  ly.resize(lx.size());
  for (long a = 0; a < na; ++a)
    for (long b = 0; b < nb; ++b) {
      lx[static_cast<size_t>(a * nb + b)] = g.x0 + (c0 + b * kLattice + 0.5) * g.gsd;
      ly[static_cast<size_t>(a * nb + b)] = g.y0 - (r0 + a * kLattice + 0.5) * g.gsd;
    }
  j.crs.to_lonlat(lx.size(), lx.data(), ly.data());  // now lon, lat
  lon.resize(static_cast<size_t>(w * h));
  lat.resize(lon.size());
  for (long r = 0; r < h; ++r) {
    const long a = r / kLattice;
    const double v = static_cast<double>(r % kLattice) / kLattice;
    for (long c = 0; c < w; ++c) {
      const long b = c / kLattice;
      const double u = static_cast<double>(c % kLattice) / kLattice;
      const size_t k00 = static_cast<size_t>(a * nb + b), k10 = k00 + 1, k01 = k00 + nb, k11 = k01 + 1;
      const size_t i = static_cast<size_t>(r * w + c);
      lon[i] = (1 - v) * ((1 - u) * lx[k00] + u * lx[k10]) + v * ((1 - u) * lx[k01] + u * lx[k11]);
      lat[i] = (1 - v) * ((1 - u) * ly[k00] + u * ly[k10]) + v * ((1 - u) * ly[k01] + u * ly[k11]);
    }
  }
}

// Stage 1: the image pixel (x, y) seen by each output pixel of the tile (NaN: none), row-major kTile x kTile,
// in w.sx, w.sy. Returns the pixels without a height.
long tile_image_points(const Job& j, long c0, long r0, Scratch& w) {
  const OrthoGrid& g = j.grid;
  const long n_lat = kTile / kLattice + 1;
  std::vector<double>&lx = w.lx, &ly = w.ly, &sx = w.sx, &sy = w.sy, &lon = w.lon, &lat = w.lat, &h = w.h;
  grid_lonlat(j, c0, r0, kTile, kTile, lx, ly, lon, lat);
  const size_t n = static_cast<size_t>(kTile * kTile);
  for (auto* v : {&h, &sx, &sy}) v->resize(n);
  if (j.surface.dem)
    j.surface.dem->heights(n, lon.data(), lat.data(), h.data());
  else
    std::fill(h.begin(), h.end(), j.surface.height);
  const RpcModel& m = j.model;
  auto folded = [&](double lo, double la) {
    return !(std::abs(lo - m.lon_off) <= kFoldBack * std::abs(m.lon_scale) && std::abs(la - m.lat_off) <= kFoldBack * std::abs(m.lat_scale));
  };
  // At one height, the projection is as smooth as the map projection: exact at the lattice's nodes and
  // bilinear between them, in each lattice cell where that bilinear value is within kLatticeTolerance of the
  // exact projection at the cell's centre (where a smooth function's bilinear error is largest); exact at
  // every pixel of the other cells. With a DEM, exact at every pixel.
  const long cells = kTile / kLattice;
  std::vector<double>&nx = w.nx, &ny = w.ny;
  std::vector<char>& smooth = w.smooth;
  smooth.assign(static_cast<size_t>(cells * cells), 0);
  if (!j.surface.dem) {
    nx.resize(lx.size());
    ny.resize(lx.size());
    for (size_t k = 0; k < lx.size(); ++k) {
      const double llh[3] = {lx[k], ly[k], j.surface.height};
      double xy[2] = {NAN, NAN};
      if (std::isfinite(lx[k]) && !folded(lx[k], ly[k])) m.project_t(llh, xy);
      nx[k] = xy[0];
      ny[k] = xy[1];
    }
    for (long a = 0; a < cells; ++a)
      for (long b = 0; b < cells; ++b) {
        const size_t k00 = static_cast<size_t>(a * n_lat + b), k10 = k00 + 1, k01 = k00 + n_lat, k11 = k01 + 1;
        const double ix = (nx[k00] + nx[k10] + nx[k01] + nx[k11]) / 4, iy = (ny[k00] + ny[k10] + ny[k01] + ny[k11]) / 4;
        if (!std::isfinite(ix) || !std::isfinite(iy)) continue;
        const double llh[3] = {(lx[k00] + lx[k10] + lx[k01] + lx[k11]) / 4, (ly[k00] + ly[k10] + ly[k01] + ly[k11]) / 4, j.surface.height};
        double xy[2];
        m.project_t(llh, xy);
        smooth[static_cast<size_t>(a * cells + b)] = std::abs(xy[0] - ix) < kLatticeTolerance && std::abs(xy[1] - iy) < kLatticeTolerance;
      }
  }
  long no_height = 0;
  for (long r = 0; r < kTile; ++r)
    for (long c = 0; c < kTile; ++c) {
      const size_t i = static_cast<size_t>(r * kTile + c);
      sx[i] = sy[i] = NAN;
      if (c0 + c >= g.width || r0 + r >= g.height || !std::isfinite(lon[i])) continue;
      if (!std::isfinite(h[i])) {
        ++no_height;
        continue;
      }
      if (folded(lon[i], lat[i])) continue;
      double xy[2];
      const long a = r / kLattice, b = c / kLattice;
      if (smooth[static_cast<size_t>(a * cells + b)]) {
        const double u = static_cast<double>(c % kLattice) / kLattice, v = static_cast<double>(r % kLattice) / kLattice;
        const size_t k00 = static_cast<size_t>(a * n_lat + b), k10 = k00 + 1, k01 = k00 + n_lat, k11 = k01 + 1;
        xy[0] = (1 - v) * ((1 - u) * nx[k00] + u * nx[k10]) + v * ((1 - u) * nx[k01] + u * nx[k11]);
        xy[1] = (1 - v) * ((1 - u) * ny[k00] + u * ny[k10]) + v * ((1 - u) * ny[k01] + u * ny[k11]);
      } else {
        const double llh[3] = {lon[i], lat[i], h[i]};
        m.project_t(llh, xy);
      }
      if (xy[0] >= -0.5 && xy[0] <= j.width - 0.5 && xy[1] >= -0.5 && xy[1] <= j.height - 0.5) {
        sx[i] = xy[0];
        sy[i] = xy[1];
      }
    }
  return no_height;
}

// The surface's heights at grid pixels (c0 + i, r0 + j), i < w, j < h: ground points as stage 1's
// (grid_lonlat), heights from the DEM at every pixel.
HeightWindow window_heights(const Job& j, long c0, long r0, long w, long h) {
  std::vector<double> lx, ly, lon, lat;
  grid_lonlat(j, c0, r0, w, h, lx, ly, lon, lat);
  HeightWindow H{c0, r0, w, h, std::vector<double>(lon.size())};
  j.surface.dem->heights(lon.size(), lon.data(), lat.data(), H.z.data());
  return H;
}

// Stage 1b (hide_occluded, with a DEM): the tile's pixels the view cannot see lose their image point.
// Returns how many valid points were hidden.
long hide_occluded_points(const Job& j, const OrthoOptions& o, long c0, long r0, Scratch& w) {
  // the tile's line of sight at its centre's height (the median of its known heights)
  std::vector<double> known;
  for (size_t i = 0; i < w.h.size(); ++i)
    if (std::isfinite(w.h[i]) && std::isfinite(w.sx[i])) known.push_back(w.h[i]);
  if (known.empty()) return 0;
  std::nth_element(known.begin(), known.begin() + static_cast<long>(known.size() / 2), known.end());
  const double hc = known[known.size() / 2], lowest = *std::min_element(known.begin(), known.end());
  const LineOfSight los = line_of_sight(j.model, j.grid, j.crs, c0 + kTile / 2.0, r0 + kTile / 2.0, hc);
  const long m = occluder_margin(los, j.top - lowest, kMaxOccluderMargin);
  if (m == 0) return 0;
  // the window reaches m pixels towards the sensor (and 2 the other way, for the bilinear surface)
  const double per_m = std::hypot(los.dc, los.dr);
  const long ex = static_cast<long>(std::ceil(m * std::abs(los.dc) / per_m)) + 2, ey = static_cast<long>(std::ceil(m * std::abs(los.dr) / per_m)) + 2;
  const long wc0 = c0 - (los.dc < 0 ? ex : 2), wr0 = r0 - (los.dr < 0 ? ey : 2);
  const HeightWindow H = window_heights(j, wc0, wr0, kTile + ex + 2, kTile + ey + 2);
  mark_hidden(H, los, c0, r0, kTile, kTile, o.hidden_tolerance, w.hidden);
  if (o.wall_slope_deg < 90) mark_walls(H, j.grid.gsd, o.wall_slope_deg, c0, r0, kTile, kTile, w.hidden);
  long n = 0;
  for (size_t i = 0; i < w.hidden.size(); ++i)
    if (w.hidden[i] && std::isfinite(w.sx[i])) {
      w.sx[i] = w.sy[i] = NAN;
      ++n;
    }
  return n;
}

// Keys' cubic convolution weights (a = -0.5) of the 4 samples around t in [0, 1) (at -1, 0, 1, 2).
inline void cubic_weights(double t, double* w) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = -0.5 * t3 + t2 - 0.5 * t;
  w[1] = 1.5 * t3 - 2.5 * t2 + 1;
  w[2] = -1.5 * t3 + 2 * t2 + 0.5 * t;
  w[3] = 0.5 * t3 - 0.5 * t2;
}

template <class T>
void store(unsigned char* dst, double v) {
  const T s = static_cast<T>(v);
  std::memcpy(dst, &s, sizeof(T));
}

// Stage 2: the tile's samples from the image window (bands rasters, all of one window).
template <class T>
long resample_tile(const Job& j, const std::vector<Raster>& win, const std::vector<double>& sx, const std::vector<double>& sy,
                   std::vector<unsigned char>& out) {
  const int B = j.bands;
  const size_t bytes = sizeof(T);
  // the output's nodata, and where a valid value equal to it goes (one step off, integer samples)
  const bool is_int = std::numeric_limits<T>::is_integer;
  const double nd = j.nodata, nd_moved = is_int ? (nd < static_cast<double>(std::numeric_limits<T>::max()) ? nd + 1 : nd - 1) : nd;
  auto invalid = [&](float v) { return std::isnan(v) || (j.src_has_nodata && v == static_cast<float>(j.src_nodata)); };
  const long wx0 = win.empty() ? 0 : win[0].x0, wy0 = win.empty() ? 0 : win[0].y0;
  const long ww = win.empty() ? 0 : win[0].width, wh = win.empty() ? 0 : win[0].height;
  auto clampx = [&](long x) { return std::min(std::max(x, 0L), j.width - 1) - wx0; };
  auto clampy = [&](long y) { return std::min(std::max(y, 0L), j.height - 1) - wy0; };
  long valid = 0;
  std::vector<double> v(static_cast<size_t>(B));
  for (size_t i = 0; i < sx.size(); ++i) {
    unsigned char* dst = out.data() + i * B * bytes;
    bool ok = std::isfinite(sx[i]);
    if (ok) {
      const double x = sx[i], y = sy[i];
      const long ix = static_cast<long>(std::floor(x)), iy = static_cast<long>(std::floor(y));
      const double fx = x - ix, fy = y - iy;
      bool done = false;
      if (j.resampling == Resampling::bicubic) {
        double wxk[4], wyk[4];
        cubic_weights(fx, wxk);
        cubic_weights(fy, wyk);
        long cx[4], cy[4];
        for (int k = 0; k < 4; ++k) {
          cx[k] = clampx(ix - 1 + k);
          cy[k] = clampy(iy - 1 + k);
        }
        bool all = true;
        for (int b = 0; b < B && all; ++b) {
          const float* d = win[static_cast<size_t>(b)].data.data();
          double s = 0;
          for (int q = 0; q < 4 && all; ++q) {
            const float* row = d + cy[q] * ww;
            double rs = 0;
            for (int p = 0; p < 4; ++p) {
              const float val = row[cx[p]];
              if (invalid(val)) {
                all = false;
                break;
              }
              rs += wxk[p] * val;
            }
            s += wyk[q] * rs;
          }
          v[static_cast<size_t>(b)] = s;
        }
        done = all;
      }
      if (!done) {
        const long x0 = clampx(ix), x1 = clampx(ix + 1), y0 = clampy(iy), y1 = clampy(iy + 1);
        for (int b = 0; b < B && ok; ++b) {
          const float* d = win[static_cast<size_t>(b)].data.data();
          const float a00 = d[y0 * ww + x0], a10 = d[y0 * ww + x1], a01 = d[y1 * ww + x0], a11 = d[y1 * ww + x1];
          // a sample of zero weight does not matter, even as nodata
          if ((invalid(a00) && (1 - fx) * (1 - fy) > 0) || (invalid(a10) && fx * (1 - fy) > 0) || (invalid(a01) && (1 - fx) * fy > 0) ||
              (invalid(a11) && fx * fy > 0)) {
            ok = false;
            break;
          }
          auto val = [&](float a) { return invalid(a) ? 0.0 : static_cast<double>(a); };
          v[static_cast<size_t>(b)] = (1 - fy) * ((1 - fx) * val(a00) + fx * val(a10)) + fy * ((1 - fx) * val(a01) + fx * val(a11));
        }
      }
      (void)wh;
    }
    if (!ok) {
      for (int b = 0; b < B; ++b) store<T>(dst + b * bytes, nd);
      continue;
    }
    ++valid;
    for (int b = 0; b < B; ++b) {
      double s = to_sample(j.type, v[static_cast<size_t>(b)]);
      if (s == nd) s = nd_moved;
      store<T>(dst + b * bytes, s);
    }
  }
  return valid;
}

long resample_any(const Job& j, const std::vector<Raster>& win, const std::vector<double>& sx, const std::vector<double>& sy,
                  std::vector<unsigned char>& out) {
  switch (j.type) {
    case SampleType::u8: return resample_tile<uint8_t>(j, win, sx, sy, out);
    case SampleType::u16: return resample_tile<uint16_t>(j, win, sx, sy, out);
    case SampleType::i16: return resample_tile<int16_t>(j, win, sx, sy, out);
    case SampleType::u32: return resample_tile<uint32_t>(j, win, sx, sy, out);
    case SampleType::i32: return resample_tile<int32_t>(j, win, sx, sy, out);
    case SampleType::f32: return resample_tile<float>(j, win, sx, sy, out);
    case SampleType::f64: return resample_tile<double>(j, win, sx, sy, out);
  }
  return 0;
}
}  // namespace

double highest_height(const OrthoSurface& surface, const OrthoGrid& g, const GridCrs& crs) {
  if (!surface.dem) return surface.height;
  const long step = std::max(4L, static_cast<long>(std::ceil(std::sqrt(static_cast<double>(g.width) * g.height / 1e6))));
  std::vector<double> x, y;
  for (long r = 0; r < g.height + step - 1; r += step)
    for (long c = 0; c < g.width + step - 1; c += step) {
      x.push_back(g.x0 + (std::min(c, g.width - 1) + 0.5) * g.gsd);
      y.push_back(g.y0 - (std::min(r, g.height - 1) + 0.5) * g.gsd);
    }
  crs.to_lonlat(x.size(), x.data(), y.data());
  std::vector<double> h(x.size());
  surface.dem->heights(x.size(), x.data(), y.data(), h.data());
  double top = NAN;
  for (double v : h)
    if (std::isfinite(v)) top = std::isfinite(top) ? std::max(top, v) : v;
  return top;
}

OrthoStats orthorectify(const std::string& image, const RpcModel& model, const OrthoGrid& grid, const GridCrs& crs,
                        const OrthoSurface& surface, const OrthoOptions& options, const std::string& out) {
  const ImageInfo info = image_info(image);
  OrthoTiffLayout layout;
  layout.grid = grid;
  layout.bands = info.bands;
  layout.type = sample_type_of(info.format, image);
  layout.rgb = info.rgb;
  const bool is_float = layout.type == SampleType::f32 || layout.type == SampleType::f64;
  // (an image's nodata outside its sample type's range, "-9999" on uint16, say: the nearest value it holds)
  layout.nodata = info.nodata ? (is_float ? *info.nodata : to_sample(layout.type, *info.nodata)) : is_float ? NAN : 0.0;
  layout.description = options.description;
  Job j{image, model, grid, crs, surface, options.resampling, info.width, info.height, info.bands, info.nodata.has_value(),
        info.nodata.value_or(0), layout.type, layout.nodata};
  if (options.hide_occluded && surface.dem) j.top = std::isfinite(surface.top) ? surface.top : highest_height(surface, grid, crs);
  OrthoTiffWriter writer(out, layout);
  const long across = layout.tiles_across(), down = layout.tiles_down();
  std::atomic<long> valid{0}, no_height{0}, hidden{0};
  std::vector<int> bands(static_cast<size_t>(info.bands));
  for (int b = 0; b < info.bands; ++b) bands[static_cast<size_t>(b)] = b;
  const int margin = options.resampling == Resampling::bicubic ? 2 : 1;
  Progress progress("ortho " + image, across * down);
  parallel_for(static_cast<size_t>(across * down), options.threads, [&](size_t k) {
    const long tx = static_cast<long>(k) % across, ty = static_cast<long>(k) / across;
    const size_t n = static_cast<size_t>(kTile * kTile);
    thread_local Scratch w;
    no_height += tile_image_points(j, tx * kTile, ty * kTile, w);
    if (std::isfinite(j.top)) hidden += hide_occluded_points(j, options, tx * kTile, ty * kTile, w);
    const std::vector<double>&sx = w.sx, &sy = w.sy;
    // the image window the tile's points need
    double xmin = std::numeric_limits<double>::infinity(), ymin = xmin, xmax = -xmin, ymax = -xmin;
    for (size_t i = 0; i < n; ++i)
      if (std::isfinite(sx[i])) {
        xmin = std::min(xmin, sx[i]);
        xmax = std::max(xmax, sx[i]);
        ymin = std::min(ymin, sy[i]);
        ymax = std::max(ymax, sy[i]);
      }
    std::vector<Raster> win;
    if (xmin <= xmax) {
      const long x0 = std::max(0L, static_cast<long>(std::floor(xmin)) - margin), y0 = std::max(0L, static_cast<long>(std::floor(ymin)) - margin);
      const long x1 = std::min(info.width, static_cast<long>(std::floor(xmax)) + margin + 2);
      const long y1 = std::min(info.height, static_cast<long>(std::floor(ymax)) + margin + 2);
      if (static_cast<double>(x1 - x0) * (y1 - y0) > kMaxWindowPixels)
        throw NumericalError(image + ": one 256 x 256 tile of the grid sees " + std::to_string(x1 - x0) + " x " + std::to_string(y1 - y0) +
                             " image pixels: the grid's pixels are far coarser than the image's (--gsd)");
      win = read_region_bands(image, bands, x0, y0, x1 - x0, y1 - y0, std::move(w.reuse));
    }
    std::vector<unsigned char>& samples = w.samples;
    samples.resize(n * static_cast<size_t>(info.bands) * static_cast<size_t>(sample_bytes(layout.type)));
    valid += resample_any(j, win, sx, sy, samples);  // no window: every sample nodata
    if (!win.empty()) w.reuse = std::move(win[0]);
    writer.write_tile(tx, ty, samples);
    progress.add();
  });
  progress.done();
  writer.close();
  OrthoStats st;
  st.pixels = grid.width * grid.height;
  st.valid = valid;
  st.no_height = no_height;
  st.hidden = hidden;
  st.bands = info.bands;
  st.type = info.format;
  st.nodata = layout.nodata;
  return st;
}

}  // namespace tpkit
