#include "tpkit/report/report_orthos.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/svg_plot.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/ground/geotiff_georef.hpp"
#include "tpkit/report/inline_jpeg.hpp"
#include "tpkit/rpc/rpc_io.hpp"

namespace tpkit {

namespace fs = std::filesystem;

namespace {

std::string esc(const std::string& s) { return svg_escape(s); }

struct Ortho {
  std::string path, name;
  GeoTiffGeoref grid;
  ImageInfo info;
};

std::string ortho_name(const std::string& path) {
  const std::string f = fs::path(path).filename().string(), suffix = ".ortho.tif";
  if (f.size() > suffix.size() && f.compare(f.size() - suffix.size(), suffix.size(), suffix) == 0)
    return f.substr(0, f.size() - suffix.size());
  return fs::path(path).stem().string();
}

std::string grid_words(const GeoTiffGeoref& g) {
  return std::to_string(g.width) + "x" + std::to_string(g.height) + " pixels, " + g.crs + ", origin (" + format_number(g.a[0]) +
         ", " + format_number(g.a[3]) + "), pixel steps (" + format_number(g.a[1]) + ", " + format_number(g.a[2]) + ", " +
         format_number(g.a[4]) + ", " + format_number(g.a[5]) + ")";
}

// Why `b` is not on `a`'s grid, "" when it is: same size, CRS and geotransform (the pixel steps within 1e-9 of
// their size, the origin within 1e-6 of a pixel: what two writers of one grid can differ by in decimals).
std::string grid_difference(const GeoTiffGeoref& a, const GeoTiffGeoref& b) {
  if (a.width != b.width || a.height != b.height)
    return "its size " + std::to_string(b.width) + "x" + std::to_string(b.height) + " is not " + std::to_string(a.width) + "x" +
           std::to_string(a.height);
  if (a.crs != b.crs) return "its CRS " + b.crs + " is not " + a.crs;
  const double pixel = std::max({std::fabs(a.a[1]), std::fabs(a.a[2]), std::fabs(a.a[4]), std::fabs(a.a[5])});
  for (int i : {1, 2, 4, 5})
    if (std::fabs(a.a[i] - b.a[i]) > 1e-9 * pixel) return "its pixel steps differ (" + grid_words(b) + ", not " + grid_words(a) + ")";
  for (int i : {0, 3})
    if (std::fabs(a.a[i] - b.a[i]) > 1e-6 * pixel) return "its origin differs (" + grid_words(b) + ", not " + grid_words(a) + ")";
  return "";
}

// A set's orthos, sorted by name, every one on the first's grid.
std::vector<Ortho> open_set(const std::vector<std::string>& paths) {
  std::vector<Ortho> set;
  for (const auto& p : paths) {
    Ortho o{p, ortho_name(p), read_geotiff_georef(p), image_info(p)};
    if (!set.empty()) {
      const std::string why = grid_difference(set[0].grid, o.grid);
      if (!why.empty())
        throw InputError(p, 0, "not on the grid of " + set[0].path + ": " + why + " (the orthos of a set overlay pixel for pixel: make them on one grid)");
    }
    for (const auto& s : set)
      if (s.name == o.name) throw InputError(p, 0, "a second ortho of " + o.name + " (the first: " + s.path + ")");
    set.push_back(std::move(o));
  }
  std::sort(set.begin(), set.end(), [](const Ortho& a, const Ortho& b) { return a.name < b.name; });
  return set;
}

// A frame of an ortho: frame pixel (u, v) covers grid pixels [x0 + u f, x0 + (u + 1) f) x [y0 + v f, ...).
struct Frame {
  cv::Mat bgr;    // CV_8UC3, nodata light grey
  cv::Mat valid;  // CV_8U, 255 where any grid pixel under it is valid
  long x0 = 0, y0 = 0;
  int f = 1;
};

const cv::Vec3b kNodata(215, 215, 215);

// The region [x0, x0 + w) x [y0, y0 + h) of the ortho reduced f times: block means of the valid pixels, read a
// band of rows at a time (memory: the band, at most 64 MiB, and the frame's sums, not the ortho), stretched
// 2-98%.
Frame render(const Ortho& o, long x0, long y0, long w, long h, int f) {
  Frame fr;
  fr.x0 = x0, fr.y0 = y0, fr.f = f;
  const int fw = static_cast<int>((w + f - 1) / f), fh = static_cast<int>((h + f - 1) / f);
  const std::vector<int> bands = o.info.bands >= 3 ? std::vector<int>{0, 1, 2} : std::vector<int>{0};
  const size_t nb = bands.size(), cells = static_cast<size_t>(fw) * fh;
  std::vector<double> sum(cells * nb, 0.0);
  std::vector<int> count(cells, 0);
  const bool has_nodata = o.info.nodata.has_value();
  const float nodata = has_nodata ? static_cast<float>(*o.info.nodata) : 0.0f;
  // rows read at once: a multiple of f, 256 rows (a tile's height: each tile decoded once) unless the band of
  // rows would take over 64 MiB as float, then fewer
  const long fit = static_cast<long>((64L << 20) / (static_cast<long>(sizeof(float)) * static_cast<long>(nb) * std::max(1L, w)));
  const long chunk = f * std::max(1L, std::min(256L, fit) / f);
  for (long r0 = 0; r0 < h; r0 += chunk) {
    const long rows = std::min(chunk, h - r0);
    const std::vector<Raster> rs = read_region_bands(o.path, bands, x0, y0 + r0, w, rows);
    for (long r = 0; r < rs[0].height; ++r) {
      const size_t v = static_cast<size_t>((r0 + r) / f);
      for (long c = 0; c < rs[0].width; ++c) {
        bool finite = true, all_nodata = has_nodata;
        for (size_t b = 0; b < nb; ++b) {
          const float s = rs[b].at(c, r);
          finite &= std::isfinite(s);
          all_nodata &= s == nodata;
        }
        if (!finite || all_nodata) continue;
        const size_t cell = v * fw + static_cast<size_t>(c / f);
        ++count[cell];
        for (size_t b = 0; b < nb; ++b) sum[cell * nb + b] += rs[b].at(c, r);
      }
    }
  }
  std::vector<float> values;
  for (size_t k = 0; k < cells; ++k)
    if (count[k])
      for (size_t b = 0; b < nb; ++b) values.push_back(static_cast<float>(sum[k * nb + b] / count[k]));
  float lo = 0, hi = 1;
  if (!values.empty()) {
    const auto at = [&](double q) {
      auto it = values.begin() + static_cast<long>(q * static_cast<double>(values.size() - 1));
      std::nth_element(values.begin(), it, values.end());
      return *it;
    };
    lo = at(0.02), hi = at(0.98);
    if (!(hi > lo)) hi = lo + 1;
  }
  fr.bgr = cv::Mat(fh, fw, CV_8UC3, cv::Scalar(kNodata[0], kNodata[1], kNodata[2]));
  fr.valid = cv::Mat::zeros(fh, fw, CV_8U);
  for (int v = 0; v < fh; ++v)
    for (int u = 0; u < fw; ++u) {
      const size_t k = static_cast<size_t>(v) * fw + u;
      if (!count[k]) continue;
      fr.valid.at<uchar>(v, u) = 255;
      auto grey = [&](size_t b) { return cv::saturate_cast<uchar>(255.0 * (sum[k * nb + b] / count[k] - lo) / (hi - lo)); };
      fr.bgr.at<cv::Vec3b>(v, u) = nb == 3 ? cv::Vec3b(grey(2), grey(1), grey(0)) : cv::Vec3b(grey(0), grey(0), grey(0));
    }
  return fr;
}

std::string jpeg_uri(const cv::Mat& bgr, int quality) {
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return jpeg_data_uri(std::vector<uint8_t>(rgb.datastart, rgb.dataend), rgb.cols, rgb.rows, 3, quality);
}

// The flicker: frames shown in turn, each for `frame_s` seconds, by a CSS animation of their opacity (the
// first frame shown where animations are off). One element per frame: <g class="frame">.
std::string flicker_svg(const std::string& id, const std::string& title, const std::vector<std::pair<std::string, std::string>>& frames,
                        int w, int h, double frame_s) {
  const size_t n = frames.size();
  const double cycle = frame_s * static_cast<double>(n);
  std::ostringstream o;
  o << "<figure class=\"ortho\"><figcaption>" << esc(title) << "</figcaption>\n<svg id=\"" << id
    << "\" class=\"flicker\" data-frames=\"" << n << "\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << w << "\" height=\"" << h + 20
    << "\" viewBox=\"0 0 " << w << ' ' << h + 20 << "\">\n<style>#" << id << " .frame{opacity:0;animation:" << id << "-k " << format_number(cycle)
    << "s step-end infinite}#" << id << " .frame:first-of-type{opacity:1}@keyframes " << id << "-k{0%{opacity:1}"
    << format_number(std::floor(100000.0 / static_cast<double>(n)) / 1000) << "%{opacity:0}100%{opacity:0}}</style>\n";
  for (size_t k = 0; k < n; ++k)
    o << "<g class=\"frame\" style=\"animation-delay:" << format_number(frame_s * static_cast<double>(k)) << "s\"><rect x=\"0\" y=\"" << h
      << "\" width=\"" << w << "\" height=\"20\" fill=\"#fff\"/><image href=\"" << frames[k].second << "\" x=\"0\" y=\"0\" width=\"" << w
      << "\" height=\"" << h << "\"/><text x=\"4\" y=\"" << h + 15 << "\" font-size=\"13\" font-family=\"sans-serif\">" << k + 1 << '/'
      << n << ' ' << esc(frames[k].first) << "</text></g>\n";
  o << "</svg></figure>\n";
  return o.str();
}

// `cells` squares along the longer side, taken in turn from a and b (frames of one size).
cv::Mat checkerboard(const Frame& a, const Frame& b, int cells) {
  const int side = std::max(1, std::max(a.bgr.cols, a.bgr.rows) / std::max(1, cells));
  cv::Mat out = a.bgr.clone();
  for (int v = 0; v < out.rows; ++v)
    for (int u = 0; u < out.cols; ++u)
      if (((u / side) + (v / side)) % 2) out.at<cv::Vec3b>(v, u) = b.bgr.at<cv::Vec3b>(v, u);
  return out;
}

// An ortho's footprint, lon/lat: the RPC model's image border at HEIGHT_OFF, else the outline of the frame's
// valid pixels. `how` says which.
struct Footprint {
  std::string name, how;
  std::vector<double> lon, lat;
};

Footprint footprint(const Ortho& o, const Frame& fr, const std::vector<std::string>& images) {
  Footprint fp{o.name, "", {}, {}};
  for (const auto& img : images) {
    if (fs::path(img).stem().string() != o.name) continue;
    try {
      const auto src = find_image_rpc(img);
      if (!src) continue;
      const ImageInfo info = image_info(img);
      const double h = src->model.height_off, W = static_cast<double>(info.width - 1), H = static_cast<double>(info.height - 1);
      constexpr int kSteps = 16;  // points per side
      for (int side = 0; side < 4; ++side)
        for (int k = 0; k < kSteps; ++k) {
          const double t = static_cast<double>(k) / kSteps;
          const double x = side == 0 ? t * W : side == 1 ? W : side == 2 ? (1 - t) * W : 0;
          const double y = side == 0 ? 0 : side == 1 ? t * H : side == 2 ? H : (1 - t) * H;
          const Eigen::Vector2d ll = src->model.localize(x, y, h);
          fp.lon.push_back(ll[0]), fp.lat.push_back(ll[1]);
        }
      fp.how = "RPC";
      return fp;
    } catch (const std::exception&) {
      fp.lon.clear(), fp.lat.clear();  // an image or model that cannot be read: the ortho's outline
    }
  }
  fp.how = "valid pixels";
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(fr.valid.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  if (contours.empty()) return fp;
  const auto& big = *std::max_element(contours.begin(), contours.end(),
                                      [](const auto& a, const auto& b) { return cv::contourArea(a) < cv::contourArea(b); });
  std::vector<cv::Point> poly;
  cv::approxPolyDP(big, poly, 1.0, true);
  GeorefToLonLat to_ll(o.grid);
  for (const auto& p : poly) {
    double lon, lat;
    const double c = fr.x0 + (p.x + 0.5) * fr.f - 0.5, r = fr.y0 + (p.y + 0.5) * fr.f - 0.5;
    if (to_ll(c, r, lon, lat)) fp.lon.push_back(lon), fp.lat.push_back(lat);
  }
  return fp;
}

const char* const kPalette[] = {"#4c78a8", "#f58518", "#e45756", "#72b7b2", "#54a24b", "#eeca3b",
                                "#b279a2", "#ff9da6", "#9d755d", "#bab0ac", "#1b9e77", "#7570b3"};

std::string footprints_svg(const std::vector<Footprint>& fps) {
  double lon0 = INFINITY, lon1 = -INFINITY, lat0 = INFINITY, lat1 = -INFINITY;
  for (const auto& f : fps)
    for (size_t k = 0; k < f.lon.size(); ++k)
      lon0 = std::min(lon0, f.lon[k]), lon1 = std::max(lon1, f.lon[k]), lat0 = std::min(lat0, f.lat[k]), lat1 = std::max(lat1, f.lat[k]);
  if (!(lon1 > lon0) || !(lat1 > lat0)) return "<p>no footprint could be drawn</p>\n";
  const double mx = 0.05 * (lon1 - lon0), my = 0.05 * (lat1 - lat0);
  lon0 -= mx, lon1 += mx, lat0 -= my, lat1 += my;
  // the panel's sides in proportion to the ground's (a degree of longitude is cos(lat) of one of latitude)
  const double ground_ratio = (lon1 - lon0) * std::cos((lat0 + lat1) / 2 * M_PI / 180) / (lat1 - lat0);
  double pw = 520, ph = pw / ground_ratio;
  if (ph > 520) ph = 520, pw = ph * ground_ratio;
  const int per_row = 3, legend_rows = static_cast<int>((fps.size() + per_row - 1) / per_row);
  SvgPlot plot(std::max(pw + 140, 640.0), ph + 110 + 18 * legend_rows);
  const int p = plot.panel(SvgPlot::spec(105, 30, pw, ph, lon0, lon1, lat0, lat1, "image footprints (WGS 84)", "longitude (deg)", "latitude (deg)"));
  std::vector<SvgPlot::LegendEntry> legend;
  for (size_t i = 0; i < fps.size(); ++i) {
    if (fps[i].lon.empty()) continue;
    std::vector<double> x = fps[i].lon, y = fps[i].lat;
    x.push_back(x.front()), y.push_back(y.front());
    const std::string colour = kPalette[i % (sizeof kPalette / sizeof *kPalette)];
    plot.polyline(p, x, y, colour, 1.5);
    legend.push_back({fps[i].name + " (" + fps[i].how + ")", colour, SvgPlot::Mark::line});
  }
  for (size_t r = 0; r * per_row < legend.size(); ++r)
    plot.legend_at(20, ph + 95 + 18.0 * static_cast<double>(r),
                   std::vector<SvgPlot::LegendEntry>(legend.begin() + static_cast<long>(r * per_row),
                                                     legend.begin() + static_cast<long>(std::min(legend.size(), (r + 1) * per_row))));
  return plot.inline_svg();
}

// What the page shows of one set: its frames over the grid and the centre, and thumbnails.
struct SetView {
  std::vector<Ortho> orthos;
  std::vector<Frame> full, zoom;
  std::vector<std::string> thumbs;  // data URIs
  std::vector<double> valid_share;
};

SetView view_set(const std::vector<std::string>& paths, const OrthoOptions& opt) {
  SetView s;
  s.orthos = open_set(paths);
  if (s.orthos.empty()) return s;
  const GeoTiffGeoref& g = s.orthos[0].grid;
  const int f = static_cast<int>(std::max<long>(1, (std::max(g.width, g.height) + opt.frame_px - 1) / opt.frame_px));
  const long zw = std::min<long>(opt.zoom_px, g.width), zh = std::min<long>(opt.zoom_px, g.height);
  for (const auto& o : s.orthos) {
    s.full.push_back(render(o, 0, 0, g.width, g.height, f));
    s.zoom.push_back(f > 1 ? render(o, (g.width - zw) / 2, (g.height - zh) / 2, zw, zh, 1) : Frame{});
    const Frame& fr = s.full.back();
    const double scale = static_cast<double>(opt.thumb_px) / std::max(fr.bgr.cols, fr.bgr.rows);
    cv::Mat thumb;
    cv::resize(fr.bgr, thumb, cv::Size(std::max(1, static_cast<int>(std::lround(fr.bgr.cols * scale))),
                                       std::max(1, static_cast<int>(std::lround(fr.bgr.rows * scale)))),
               0, 0, cv::INTER_AREA);
    s.thumbs.push_back(jpeg_uri(thumb, opt.jpeg_quality));
    s.valid_share.push_back(static_cast<double>(cv::countNonZero(fr.valid)) / static_cast<double>(fr.valid.total()));
  }
  return s;
}

std::vector<std::pair<std::string, std::string>> frames_of(const SetView& s, bool zoom, int quality) {
  std::vector<std::pair<std::string, std::string>> out;
  for (size_t i = 0; i < s.orthos.size(); ++i) out.push_back({s.orthos[i].name, jpeg_uri((zoom ? s.zoom : s.full)[i].bgr, quality)});
  return out;
}

}  // namespace

std::vector<std::string> ortho_inputs(const std::vector<std::string>& args, const std::string& option) {
  std::vector<std::string> out;
  for (const auto& a : args) {
    if (!fs::exists(a)) throw InputError(option + " " + a + ": no such file or folder");
    if (!fs::is_directory(a)) {
      out.push_back(a);
      continue;
    }
    std::vector<std::string> found;
    for (const auto& e : fs::directory_iterator(a)) {
      const std::string f = e.path().filename().string();
      if (e.is_regular_file() && f.size() > 10 && f.compare(f.size() - 10, 10, ".ortho.tif") == 0) found.push_back(e.path().string());
    }
    if (found.empty()) throw InputError(option + " " + a + ": no *.ortho.tif file in the folder");
    std::sort(found.begin(), found.end());
    out.insert(out.end(), found.begin(), found.end());
  }
  return out;
}

std::string orthos_html(const std::vector<std::string>& before, const std::vector<std::string>& after, const OrthoOptions& opt) {
  if (before.empty() && after.empty()) return "";
  const SetView b = view_set(before, opt), a = view_set(after, opt);
  std::vector<std::pair<const char*, const SetView*>> sets;
  if (!b.orthos.empty()) sets.push_back({"before", &b});
  if (!a.orthos.empty()) sets.push_back({"after", &a});
  const SetView& first = *sets[0].second;
  std::ostringstream o;
  o << "<section id=\"orthos\"><h2>Orthoimages</h2>\n<p>";
  for (const auto& [label, s] : sets)
    o << s->orthos.size() << " orthos " << label << " the adjustment on " << esc(grid_words(s->orthos[0].grid)) << ".<br>";
  if (sets.size() == 2 && !grid_difference(b.orthos[0].grid, a.orthos[0].grid).empty())
    o << "<span class=\"error\">the orthos before and after lie on different grids: compare each flicker on its own.</span><br>";
  if (sets.size() == 2) {
    std::vector<std::string> only;
    for (const auto& x : b.orthos)
      if (std::none_of(a.orthos.begin(), a.orthos.end(), [&](const Ortho& y) { return y.name == x.name; })) only.push_back(x.name + " (before only)");
    for (const auto& x : a.orthos)
      if (std::none_of(b.orthos.begin(), b.orthos.end(), [&](const Ortho& y) { return y.name == x.name; })) only.push_back(x.name + " (after only)");
    for (const auto& s : only) o << "<span class=\"error\">" << esc(s) << "</span> ";
  }
  o << "</p>\n";
  const int f = first.full[0].f;
  o << "<h3>Flicker between the dates" << (f > 1 ? " (whole grid, reduced " + std::to_string(f) + " times)" : "") << "</h3>\n<div class=\"row\">\n";
  for (const auto& [label, s] : sets)
    o << flicker_svg(std::string("flicker-") + label, std::string(label) + " the adjustment", frames_of(*s, false, opt.jpeg_quality),
                     s->full[0].bgr.cols, s->full[0].bgr.rows, opt.frame_s);
  o << "</div>\n";
  if (f > 1) {
    o << "<h3>Flicker at full resolution (the grid's centre)</h3>\n<div class=\"row\">\n";
    for (const auto& [label, s] : sets)
      o << flicker_svg(std::string("flicker-zoom-") + label, std::string(label) + " the adjustment", frames_of(*s, true, opt.jpeg_quality),
                       s->zoom[0].bgr.cols, s->zoom[0].bgr.rows, opt.frame_s);
    o << "</div>\n";
  }
  if (first.orthos.size() >= 2) {
    o << "<h3>Checkerboard of two dates</h3>\n<div class=\"row\">\n";
    for (const auto& [label, s] : sets) {
      if (s->orthos.size() < 2) continue;
      const cv::Mat cb = checkerboard(s->full[0], s->full[1], opt.checker_cells);
      o << "<figure class=\"ortho checkerboard\" id=\"checkerboard-" << label << "\"><figcaption>" << label << " the adjustment: "
        << esc(s->orthos[0].name) << " and " << esc(s->orthos[1].name) << "</figcaption><img alt=\"checkerboard " << label << "\" src=\""
        << jpeg_uri(cb, opt.jpeg_quality) << "\" width=\"" << cb.cols << "\" height=\"" << cb.rows << "\"></figure>\n";
    }
    o << "</div>\n";
  }
  std::vector<Footprint> fps;
  for (size_t i = 0; i < first.orthos.size(); ++i) fps.push_back(footprint(first.orthos[i], first.full[i], opt.images));
  o << "<h3>Footprints</h3>\n" << footprints_svg(fps);
  o << "<h3>Thumbnails</h3>\n";
  for (const auto& [label, s] : sets) {
    o << "<div class=\"row thumbs\" id=\"thumbs-" << label << "\">\n";
    for (size_t i = 0; i < s->orthos.size(); ++i)
      o << "<figure class=\"ortho\"><img alt=\"" << esc(s->orthos[i].name) << "\" src=\"" << s->thumbs[i] << "\"><figcaption>" << label << ": "
        << esc(s->orthos[i].name) << ", " << format_figure(100 * s->valid_share[i], 3) << "% valid</figcaption></figure>\n";
    o << "</div>\n";
  }
  o << "</section>\n";
  return o.str();
}

}  // namespace tpkit
