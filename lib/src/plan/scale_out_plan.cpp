#include "tpkit/plan/scale_out_plan.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/match/sift_tiles.hpp"

namespace tpkit {

namespace fs = std::filesystem;

namespace {
// The footprint of an image from its model (see image_footprint).
std::optional<Footprint> footprint_of(const std::string& path, const RpcSource& rpc, long width, long height) {
  if (width <= 0 || height <= 0) return std::nullopt;
  // the image's border, 4 points a side (corners included), at both ends of the model's height range:
  // the outline of every ground point the image can see; and at its middle height, for the overlap
  Footprint f;
  auto border = [&](double h, std::vector<std::array<double, 2>>& out) {
    for (int k = 0; k < 16; ++k) {
      const int side = k / 4, t = k % 4;  // top, right, bottom, left; t = 0..3 along it
      const double u = t / 4.0, X = width - 0.5, Y = height - 0.5;
      const double x = side == 0 ? -0.5 + u * width : side == 1 ? X : side == 2 ? X - u * width : -0.5;
      const double y = side == 0 ? -0.5 : side == 1 ? -0.5 + u * height : side == 2 ? Y : Y - u * height;
      const Eigen::Vector2d ll = rpc.model.localize(x, y, h);
      out.push_back({ll.x(), ll.y()});
    }
  };
  try {
    border(0.5 * (rpc.model.height_min() + rpc.model.height_max()), f.middle);
    for (double h : {rpc.model.height_min(), rpc.model.height_max()}) border(h, f.lonlat);
  } catch (const NumericalError&) {
    warn(path + ": its RPC model (" + rpc.path + ") does not localize the image's border: paired with every image");
    return std::nullopt;
  }
  return f;
}
}  // namespace

std::optional<Footprint> image_footprint(const std::string& path, long width, long height) {
  const std::optional<RpcSource> rpc = find_image_rpc(path);  // a broken model is bad input: thrown
  if (!rpc) return std::nullopt;
  return footprint_of(path, *rpc, width, height);
}

bool footprints_may_overlap(const PlanImage& a, const PlanImage& b) {
  if (!a.footprint || !b.footprint || a.footprint->lonlat.empty() || b.footprint->lonlat.empty()) return true;
  auto box = [](const Footprint& f) {
    std::array<double, 4> r{1e300, 1e300, -1e300, -1e300};
    for (const auto& p : f.lonlat)
      r = {std::min(r[0], p[0]), std::min(r[1], p[1]), std::max(r[2], p[0]), std::max(r[3], p[1])};
    return r;
  };
  const auto p = box(*a.footprint), q = box(*b.footprint);
  return p[0] <= q[2] && q[0] <= p[2] && p[1] <= q[3] && q[1] <= p[3];
}

namespace {
using Polygon = std::vector<Eigen::Vector2d>;
double signed_area(const Polygon& p) {
  double a = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d &u = p[i], &v = p[(i + 1) % p.size()];
    a += u.x() * v.y() - v.x() * u.y();
  }
  return 0.5 * a;
}
// Sutherland-Hodgman: the part of `subject` inside the convex polygon `clip` (both counter-clockwise).
// A footprint at one height is the image border through the model: convex up to the model's
// distortion, which is far below what a ratio of areas needs.
Polygon clip_polygon(Polygon subject, const Polygon& clip) {
  for (size_t e = 0; e < clip.size() && !subject.empty(); ++e) {
    const Eigen::Vector2d a = clip[e], b = clip[(e + 1) % clip.size()], d = b - a;
    auto side = [&](const Eigen::Vector2d& p) { return d.x() * (p.y() - a.y()) - d.y() * (p.x() - a.x()); };
    Polygon out;
    for (size_t i = 0; i < subject.size(); ++i) {
      const Eigen::Vector2d p = subject[i], q = subject[(i + 1) % subject.size()];
      const double sp = side(p), sq = side(q);
      if (sp >= 0) out.push_back(p);
      if ((sp >= 0) != (sq >= 0)) out.push_back(p + (q - p) * (sp / (sp - sq)));
    }
    subject.swap(out);
  }
  return subject;
}
}  // namespace

double footprint_overlap(const PlanImage& a, const PlanImage& b) {
  if (!a.footprint || !b.footprint || a.footprint->middle.size() < 3 || b.footprint->middle.size() < 3) return 1;
  // a local frame: longitudes scaled by the cosine of the mean latitude (a ratio of areas needs no more)
  const double lat0 = 0.5 * (a.footprint->middle[0][1] + b.footprint->middle[0][1]) * M_PI / 180;
  auto local = [&](const Footprint& f) {
    Polygon p;
    for (const auto& ll : f.middle) p.emplace_back(ll[0] * std::cos(lat0), ll[1]);
    if (signed_area(p) < 0) std::reverse(p.begin(), p.end());
    return p;
  };
  const Polygon pa = local(*a.footprint), pb = local(*b.footprint);
  const double aa = signed_area(pa), ab = signed_area(pb);
  if (!(aa > 0) || !(ab > 0)) return 1;
  const Polygon both = clip_polygon(pa, pb);
  const double inter = both.size() < 3 ? 0 : std::max(0.0, signed_area(both));
  return std::min(1.0, inter / std::min(aa, ab));
}

std::vector<PlanImage> plan_images(const std::vector<std::string>& paths) {
  if (paths.size() < 2) throw UsageError("a plan needs two images or more, got " + std::to_string(paths.size()));
  std::vector<PlanImage> out;
  for (const auto& p : paths) {
    shell_quote(p);  // refuses a newline
    const ImageInfo info = image_info(p);
    std::error_code ec;
    const fs::path abs = fs::absolute(p, ec).lexically_normal();
    for (const auto& q : out)
      if (q.path == abs.string()) throw UsageError("the image " + p + " is listed twice");
    const std::optional<RpcSource> rpc = find_image_rpc(p);  // a broken model is bad input: thrown
    out.push_back({abs.string(), info.width, info.height, rpc ? footprint_of(p, *rpc, info.width, info.height) : std::nullopt,
                   rpc.has_value()});
  }
  return out;
}

std::vector<std::string> read_image_list(const std::string& path) {
  constexpr size_t kMaxPath = 4096;  // PATH_MAX
  std::ifstream in = open_input_file(path, InputKind::file);
  std::vector<std::string> out;
  std::string line;
  for (long n = 1; read_text_line(in, line, path, n, kMaxPath); ++n) {
    if (n == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);  // a UTF-8 byte order mark (Notepad's)
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    out.push_back(line);
  }
  return out;
}

std::vector<std::array<long, 4>> plan_regions(long width, long height, long tile, long overlap) {
  std::vector<std::array<long, 4>> out;
  for (long y = 0; y < height; y += tile)
    for (long x = 0; x < width; x += tile) {
      const long x0 = std::max(0L, x - overlap), y0 = std::max(0L, y - overlap);
      const long x1 = std::min(width, x + tile + overlap), y1 = std::min(height, y + tile + overlap);
      out.push_back({x0, y0, x1 - x0, y1 - y0});
    }
  return out;
}

std::vector<std::array<long, 4>> detection_blocks(long width, long height, long tile, long regions) {
  std::vector<std::array<long, 4>> out;
  const long w = tile * regions;
  for (long y = 0; y < height; y += tile)
    for (long x = 0; x < width; x += w) out.push_back({x, y, std::min(w, width - x), std::min(tile, height - y)});
  return out;
}

std::string shell_quote(const std::string& text) {
  if (text.find('\n') != std::string::npos || text.find('\r') != std::string::npos || text.find('\0') != std::string::npos)
    throw UsageError("a path with a line break cannot go into a job file: " + text.substr(0, text.find_first_of("\r\n")) + "...");
  std::string q = "'";
  for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

namespace {

std::string pair_name(const std::array<size_t, 2>& p) {
  return "pair-" + std::to_string(p[0] + 1) + "-" + std::to_string(p[1] + 1);
}

std::string tool(const PlanOptions& o, const std::string& name) {
  return o.bin.empty() ? name : shell_quote((fs::path(o.bin) / name).string());
}

std::string in_work(const PlanOptions& o, const std::string& rel) { return shell_quote((fs::path(o.work) / rel).string()); }

std::string match_args(const PlanOptions& o) {
  std::string s = " --threads " + std::to_string(o.threads);
  if (o.detect_tile > 0) s += " --tile " + std::to_string(o.detect_tile);
  for (const auto& a : o.match_args) s += " " + shell_quote(a);
  return s;
}

// " --region X0 Y0 W H"
std::string region_arg(const std::array<long, 4>& r) {
  return " --region " + std::to_string(r[0]) + " " + std::to_string(r[1]) + " " + std::to_string(r[2]) + " " + std::to_string(r[3]);
}

// The adjust and ground stages after the chain (see the header), or the reason why not.
void add_adjustment(Plan& p, const std::vector<PlanImage>& images, const std::vector<char>& paired, const PlanOptions& o) {
  using Mode = PlanOptions::Adjust;
  if (o.adjust_model != "shift" && o.adjust_model != "drift" && o.adjust_model != "affine")
    throw UsageError("--adjust-model " + o.adjust_model + ": expected shift, drift or affine");
  std::vector<size_t> chained;
  for (size_t i = 0; i < images.size(); ++i)
    if (paired[i]) chained.push_back(i);
  std::vector<std::string> paths;
  for (const PlanImage& im : images) paths.push_back(im.path);
  std::vector<size_t> fixed;  // named as the plan names them, whatever the spelling of --fixed
  for (const auto& f : o.fixed) {
    const int i = image_index(f, paths);
    if (i < 0) throw UsageError("--fixed " + f + ": " + (i == -2 ? "ambiguous among" : "not one of") + " the plan's images");
    if (!paired[static_cast<size_t>(i)]) throw UsageError("--fixed " + f + ": left out of the plan (it overlaps no other image)");
    fixed.push_back(static_cast<size_t>(i));
  }
  if (o.adjust == Mode::off) return;
  // what the adjustment needs of the images, else the reason
  std::string reason;
  bool no_model = false;
  std::vector<std::string> stems;
  for (size_t i : chained) {
    const fs::path path(images[i].path);
    if (!images[i].rpc) {
      reason = images[i].path + ": no RPC model (no tag 50844 and no sidecar, see rpc-adjust(1)): the adjustment needs one for every image";
      no_model = true;
      break;
    }
    if (images[i].path.find('=') != std::string::npos) {
      reason = images[i].path + ": a '=' in the path cannot go into tp-ground's --rpc IMAGE=FILE";
      break;
    }
    const std::string stem = path.stem().string();
    if (std::find(stems.begin(), stems.end(), stem) != stems.end()) {
      reason = images[i].path + ": another image of the plan is also named " + stem + ".*: rpc-adjust names the adjusted models by it";
      break;
    }
    stems.push_back(stem);
  }
  if (!reason.empty()) {
    if (o.adjust == Mode::on) {
      if (no_model) throw InputError(reason);
      throw UsageError(reason);
    }
    warn(reason + "; the plan ends with the chain (tracks.tracks), without the adjust and ground stages");
    return;
  }
  const std::string threads = " --threads " + std::to_string(o.threads);
  std::string imgs;
  for (size_t i : chained) imgs += " " + shell_quote(images[i].path);
  // the refine stage: every view of a track refined together (and the views it lacks); the chain (made
  // after this, by make_plan) then keeps the matches the pairs could not refine, which tp-refine refines
  // or drops
  const std::string tracks_target = o.refine ? "refined.tracks" : "tracks.tracks";
  if (o.refine) {
    PlanJob refine{tracks_target, {"tracks.tracks"}, {}, tool(o, "tp-refine") + " -q" + imgs + " --tracks " + in_work(o, "tracks.tracks") + threads};
    for (const auto& a : o.refine_args) refine.command += " " + shell_quote(a);
    refine.command += " -o " + in_work(o, tracks_target);
    p.refine.push_back(refine);
  }
  const std::string tracks = in_work(o, tracks_target);
  PlanJob adjust{"adjusted/rpc.bias", {tracks_target}, {},
                 tool(o, "rpc-adjust") + imgs + " --tracks " + tracks + " --model " + o.adjust_model};
  for (size_t i : fixed) adjust.command += " --fixed " + shell_quote(images[i].path);
  adjust.command += threads;
  for (const auto& a : o.adjust_args) adjust.command += " " + shell_quote(a);
  adjust.command += " -o " + in_work(o, "adjusted");
  p.adjust.push_back(adjust);
  PlanJob ground{"ground.points", {"adjusted/rpc.bias", tracks_target}, {}, tool(o, "tp-ground") + imgs + " --tracks " + tracks};
  for (size_t i : chained)
    ground.command += " --rpc " + shell_quote(images[i].path + "=" + (fs::path(o.work) / "adjusted" / (fs::path(images[i].path).stem().string() + "_rpc.txt")).string());
  ground.command += threads;
  for (const auto& a : o.ground_args) ground.command += " " + shell_quote(a);
  ground.command += " -o " + in_work(o, "ground.points");
  p.ground.push_back(ground);
  if (o.ortho_args.empty()) return;
  // the orthos of every image through its adjusted model, on one grid (one tp-ortho run)
  PlanJob ortho{"orthos/" + fs::path(images[chained[0]].path).stem().string() + ".ortho.tif", {"adjusted/rpc.bias"}, {},
                tool(o, "tp-ortho") + " -q" + imgs};
  for (size_t i : chained)
    ortho.command += " --rpc " + shell_quote(images[i].path + "=" + (fs::path(o.work) / "adjusted" / (fs::path(images[i].path).stem().string() + "_rpc.txt")).string());
  ortho.command += threads;
  for (const auto& a : o.ortho_args) ortho.command += " " + shell_quote(a);
  ortho.command += " -o " + in_work(o, "orthos");
  p.ortho.push_back(ortho);
}

}  // namespace

Plan make_plan(const std::vector<PlanImage>& images, const PlanOptions& o) {
  if (o.tile < 256) throw UsageError("--tile must be at least 256 pixels");
  if (!(o.min_overlap >= 0 && o.min_overlap <= 1)) throw UsageError("--min-overlap must be between 0 and 1");
  if (o.overlap < 0) throw UsageError("--overlap must be >= 0");
  if (o.detect_tile != 0 && o.detect_tile < 256) throw UsageError("--detect-tile must be 0 or at least 256 pixels");
  if (o.detect_regions < 1) throw UsageError("--detect-regions must be at least 1");
  Plan p;
  for (size_t i = 0; i < images.size(); ++i)
    for (size_t j = i + 1; j < images.size(); ++j)
      if (footprints_may_overlap(images[i], images[j])) {
        if (footprint_overlap(images[i], images[j]) >= o.min_overlap)
          p.pairs.push_back({i, j});
        else
          ++p.pairs_below_overlap;
      }
  if (p.pairs.empty()) throw UsageError("no two images of the list overlap");
  std::vector<char> paired(images.size(), 0);
  for (const auto& pr : p.pairs) paired[pr[0]] = paired[pr[1]] = 1;
  for (size_t i = 0; i < images.size(); ++i)
    if (!paired[i]) warn(images[i].path + ": its RPC footprint meets no other image's: left out of the plan");
  const std::string quiet = " -q";
  std::vector<std::string> pair_files;
  for (const auto& pr : p.pairs) {
    const PlanImage &a = images[pr[0]], &b = images[pr[1]];
    const std::string name = pair_name(pr), geo = "geometry/" + name + ".geometry";
    const std::string imgs = " " + shell_quote(a.path) + " " + shell_quote(b.path);
    p.geometry.push_back({geo, {}, {}, tool(o, "tp-match") + quiet + match_args(o) + " --write-geometry " + in_work(o, geo) + imgs});
    PlanJob merge{"pairs/" + name + ".matches", {}, {}, tool(o, "tp-merge") + quiet + " -o " + in_work(o, "pairs/" + name + ".matches")};
    const auto regions = plan_regions(a.width, a.height, o.tile, o.overlap);
    for (size_t k = 0; k < regions.size(); ++k) {
      const auto& r = regions[k];
      const std::string out = "tiles/" + name + "/tile-" + std::to_string(k + 1) + ".matches";
      p.tiles.push_back({out, {geo}, {pr[0], pr[1]},
                         tool(o, "tp-match") + quiet + match_args(o) + " --geometry " + in_work(o, geo) + region_arg(r) + " --cache " + in_work(o, "cache") + " -o " + in_work(o, out) + imgs});
      merge.depends.push_back(out);
      merge.command += " " + in_work(o, out);
    }
    pair_files.push_back(merge.target);
    p.merge.push_back(merge);
  }
  // detection: every image of a pair once, through the geometry of its first pair (which holds its
  // stretch), in blocks of its own pixels (detection_blocks); the region jobs of a pair wait for every
  // block of both its images
  p.image_detections.resize(images.size());
  for (size_t i = 0; i < images.size(); ++i) {
    const auto pr = std::find_if(p.pairs.begin(), p.pairs.end(), [&](const auto& q) { return q[0] == i || q[1] == i; });
    if (pr == p.pairs.end()) continue;
    const std::string geo = "geometry/" + pair_name(*pr) + ".geometry";
    const std::string imgs = " " + shell_quote(images[(*pr)[0]].path) + " " + shell_quote(images[(*pr)[1]].path);
    const auto blocks = detection_blocks(images[i].width, images[i].height, o.tile, o.detect_regions);
    const long dt = o.detect_tile > 0 ? o.detect_tile : SiftOptions{}.tile;
    const auto grid = tile_grid(images[i].width, images[i].height, dt, 0);
    for (size_t k = 0; k < blocks.size(); ++k) {
      const auto& r = blocks[k];
      if (tiles_starting_in(grid, r[0], r[1], r[2], r[3]).empty()) continue;  // a block without a tile of its own
      const std::string out = "detect/image-" + std::to_string(i + 1) + "/block-" + std::to_string(k + 1) + ".detection";
      p.detect.push_back({out, {geo}, {},
                          tool(o, "tp-match") + quiet + match_args(o) + " --geometry " + in_work(o, geo) + " --detect " +
                              std::string((*pr)[0] == i ? "1" : "2") + region_arg(r) + " --cache " +
                              in_work(o, "cache") + " -o " + in_work(o, out) + imgs});
      p.image_detections[i].push_back(out);
    }
  }
  // where every chained image has a model, the views the models contradict by more than 1 px after
  // each pair's bias are dropped (tp-chain --rpc-check): rpc-adjust would flag their whole tracks
  bool all_models = true;
  for (size_t i = 0; i < images.size(); ++i)
    if (paired[i] && !images[i].rpc) all_models = false;
  // the stages after the chain first: with the refine stage the chain also keeps the unrefined matches
  add_adjustment(p, images, paired, o);
  PlanJob chain{"tracks.tracks", pair_files, {},
                tool(o, "tp-chain") + quiet + (all_models ? " --rpc-check 1 --threads " + std::to_string(o.threads) : "") +
                    (p.refine.empty() ? "" : " --unrefined") + " --images"};
  for (size_t i = 0; i < images.size(); ++i)
    if (paired[i]) chain.command += " " + shell_quote(images[i].path);
  chain.command += " -o " + in_work(o, "tracks.tracks");
  for (const auto& f : pair_files) chain.command += " " + in_work(o, f);
  p.chain.push_back(chain);
  return p;
}

std::vector<PlanStage> plan_stages(const Plan& p) {
  std::vector<PlanStage> out;
  for (const PlanStage& s : std::initializer_list<PlanStage>{{"geometry", &p.geometry}, {"detect", &p.detect}, {"tiles", &p.tiles},
                                                             {"merge", &p.merge}, {"chain", &p.chain}, {"refine", &p.refine}, {"adjust", &p.adjust},
                                                             {"ground", &p.ground}, {"ortho", &p.ortho}})
    if (!s.jobs->empty()) out.push_back(s);
  return out;
}

std::string plan_result(const Plan& p) { return p.ground.empty() ? "tracks.tracks" : p.ground.back().target; }

std::vector<std::string> plan_tool_args(const std::string& text, const std::string& which, const std::string& option_name) {
  const bool adjust = which == "rpc-adjust", ortho = which == "tp-ortho", refine = which == "tp-refine";
  std::vector<std::string> refused = {"-o", "--out", "--output", "--tracks", "--threads", "--rpc"};
  if (adjust) refused.insert(refused.end(), {"--model", "--fixed"});
  if (ortho) refused.insert(refused.end(), {"--compare", "--tile"});
  auto why = [&](const std::string& opt) -> std::string {
    if (opt == "--model") return "it is tp-plan's --adjust-model";
    if (opt == "--fixed") return "it is tp-plan's --fixed";
    if (opt == "--threads") return "it is tp-plan's --threads";
    if (opt == "--rpc" && ortho) return "the orthos are made through the adjusted models";
    if (opt == "--compare" || opt == "--tile") return "the ortho stage makes orthos; compare them with tp-ortho --compare";
    if (opt == "--rpc") return "the models are those found beside the images, as for the footprints and tp-match";
    return "tp-plan sets it (the work folder's files)";
  };
  auto absolute = [](const std::string& f) { return f == "-" ? f : fs::absolute(f).lexically_normal().string(); };
  // the options that name files (and folders), read and written by the jobs in the work folder: one file
  // each, or (--check) files until the next option
  const std::vector<std::string> one_file = adjust  ? std::vector<std::string>{"--dem", "--gcp"}
                                           : ortho ? std::vector<std::string>{"--dem", "--like"}
                                           : refine ? std::vector<std::string>{"--reference"}
                                                   : std::vector<std::string>{"--compare", "--align", "--dz", "--models"};
  const std::string many_files = adjust ? "--check" : "";
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string file_option;  // the option whose file names follow
  bool heights = false;
  for (std::string a; in >> a;) {
    heights = heights || a.rfind("--dem", 0) == 0 || a.rfind("--height", 0) == 0;
    const bool is_option = a.size() > 1 && a[0] == '-' && !(std::isdigit(static_cast<unsigned char>(a[1])) || a[1] == '.');
    if (is_option) {
      file_option.clear();
      const std::string name = a.substr(0, a.find('='));
      for (const auto& r : refused)
        if (name == r || (r == "-o" && a.rfind("-o", 0) == 0 && a.rfind("--", 0) != 0))
          throw UsageError(option_name + ": " + r + " is refused there: " + why(r));
      if (name == many_files || std::find(one_file.begin(), one_file.end(), name) != one_file.end()) {
        if (name.size() < a.size()) {
          a = name + "=" + absolute(a.substr(name.size() + 1));
        } else {
          file_option = name;
        }
      }
      out.push_back(a);
      continue;
    }
    if (!file_option.empty()) {
      a = absolute(a);
      if (file_option != many_files) file_option.clear();
    }
    out.push_back(a);
  }
  if (ortho && !out.empty() && !heights) throw UsageError(option_name + ": give the orthos' heights, --dem FILE or --height H");
  return out;
}

std::string plan_makefile(const Plan& p) {
  std::ostringstream s;
  s << "# tpkit plan (tp-plan): make -C WORK -f plan.mk -j N\n"
       "# Targets are relative to the work folder; every command line is the job files' own.\n"
       ".PHONY: tpkit-all\n"
       ".DELETE_ON_ERROR:\n"
       "tpkit-all: " << plan_result(p) << (p.ortho.empty() ? std::string() : " " + p.ortho.back().target) << "\n";
  auto dollars = [](const std::string& c) {
    std::string r;
    for (char ch : c) r += ch == '$' ? std::string("$$") : std::string(1, ch);
    return r;
  };
  // each image's detection targets once (a region job names the variables of its two images)
  auto detections_of = [](size_t i) { return "detect-image-" + std::to_string(i + 1); };
  for (size_t i = 0; i < p.image_detections.size(); ++i) {
    if (p.image_detections[i].empty()) continue;
    s << detections_of(i) << " :=";
    for (const auto& t : p.image_detections[i]) s << " " << t;
    s << "\n";
  }
  for (const PlanStage& stage : plan_stages(p))
    for (const PlanJob& j : *stage.jobs) {
      s << j.target << ":";
      for (const auto& d : j.depends) s << " " << d;
      for (size_t i : j.detections) s << " $(" << detections_of(i) << ")";
      s << "\n\t" << dollars(j.command) << "\n";
    }
  return s.str();
}

std::string plan_job_file(const std::vector<PlanJob>& jobs) {
  std::string s;
  for (const PlanJob& j : jobs) s += j.command + "\n";
  return s;
}

std::string plan_sbatch_script() {
  return "#!/bin/bash\n"
         "# tpkit plan (tp-plan): one job of a job array runs line $SLURM_ARRAY_TASK_ID of the job file $1.\n"
         "# Submitted by submit-slurm.sh: sbatch --array=1-N slurm-array.sbatch JOBFILE\n"
         "set -euo pipefail\n"
         "line=$(sed -n \"${SLURM_ARRAY_TASK_ID}p\" \"$1\")\n"
         "if [ -z \"$line\" ]; then echo \"no job ${SLURM_ARRAY_TASK_ID} in $1\" >&2; exit 1; fi\n"
         "exec bash -c \"$line\"\n";
}

std::string plan_slurm_submit(const Plan& p, const PlanOptions& o) {
  const std::vector<PlanStage> stages = plan_stages(p);
  std::string names;
  for (const auto& st : stages) names += (names.empty() ? "" : ", ") + st.name;
  std::ostringstream s;
  s << "#!/bin/bash\n"
       "# tpkit plan (tp-plan): submits the stages " << names << " as Slurm job arrays, each\n"
       "# after the previous one succeeded (afterok). Usage: bash submit-slurm.sh [--wait] [SBATCH OPTIONS...]\n"
       "# The sbatch options go to every stage; --wait returns when the last stage ends, with its status.\n"
       "# Prints each stage's job id.\n"
       "set -euo pipefail\n"
       "W=" << shell_quote(o.work) << "\n"
       "# sbatch expands %x, %j, ... in --output: a '%' of the folder's path is written %%; a backslash in it\n"
       "# would turn the expansion off (every job of a stage writing one log file)\n"
       "case $W in *\\\\*) echo \"submit-slurm.sh: $W: a backslash in the path turns off sbatch's %a in --output\" >&2; exit 2 ;; esac\n"
       "L=${W//\"%\"/\"%%\"}/logs\n"
       "wait=()\n"
       "if [ \"${1:-}\" = --wait ]; then wait=(--wait); shift; fi\n"
       "opts=(\"$@\")\n"
       "dep=()\n"
       "submit() {  # STAGE JOBS [--wait]\n"
       "  local id\n"
       "  id=$(sbatch --parsable \"${@:3}\" \"${dep[@]}\" \"${opts[@]}\" --job-name=\"tpkit-$1\" --array=\"1-$2\" \\\n"
       "       --cpus-per-task=" << o.threads << " --output=\"$L/$1-%a.log\" \"$W/slurm-array.sbatch\" \"$W/jobs/$1.jobs\")\n"
       "  id=${id%%;*}\n"
       "  echo \"$1 $id\"\n"
       "  dep=(--dependency=\"afterok:$id\")\n"
       "}\n";
  for (size_t k = 0; k < stages.size(); ++k)
    s << "submit " << stages[k].name << " " << stages[k].jobs->size() << (k + 1 == stages.size() ? " \"${wait[@]}\"" : "") << "\n";
  return s.str();
}

std::string plan_parallel_runner(const Plan& p, const PlanOptions& o) {
  std::string names;
  for (const auto& st : plan_stages(p)) names += (names.empty() ? "" : " ") + st.name;
  return "#!/bin/bash\n"
         "# tpkit plan (tp-plan): runs the stages with GNU parallel, one after the other.\n"
         "# Usage: bash run-parallel.sh [PARALLEL OPTIONS...]   (e.g. -j 8, --sshloginfile FILE)\n"
         "set -euo pipefail\n"
         "W=" +
         shell_quote(o.work) +
         "\n"
         "for s in " + names + "; do\n"
         "  parallel --halt now,fail=1 --joblog \"$W/logs/parallel-$s.joblog\" \"$@\" < \"$W/jobs/$s.jobs\"\n"
         "done\n";
}

namespace {
// A work folder already used: the same plan, else refused (see the header).
void check_work_folder(const fs::path& W, const std::string& makefile) {
  std::error_code ec;
  if (!fs::exists(W, ec)) return;
  if (!fs::is_directory(W, ec)) throw InputError(W.string(), 0, "cannot plan into it: not a folder");
  const fs::path mk = W / "plan.mk";
  if (fs::is_regular_file(mk, ec)) {
    std::ifstream in(mk, std::ios::binary);
    std::ostringstream old;
    old << in.rdbuf();
    if (old.str() == makefile) return;  // the same plan: its outputs are this plan's, make resumes it
    throw UsageError(W.string() + ": holds another plan (its plan.mk differs: other images, another order or other "
                                  "options), whose outputs would stand for other pairs: plan into a new folder, or empty this one");
  }
  for (const char* d : {"geometry", "detect", "tiles", "pairs", "tracks.tracks", "refined.tracks", "adjusted", "ground.points", "orthos"}) {
    const fs::path sub = W / d;
    bool used = fs::is_regular_file(sub, ec);
    if (fs::is_directory(sub, ec))
      for (auto it = fs::recursive_directory_iterator(sub, ec); !used && it != fs::recursive_directory_iterator(); it.increment(ec))
        used = !it->is_directory(ec);
    if (used)
      throw UsageError(W.string() + ": holds outputs of a plan (" + std::string(d) +
                       ") but no plan.mk: plan into a new folder, or empty this one");
  }
}
}  // namespace

void write_plan(const Plan& p, const PlanOptions& o) {
  const fs::path W(o.work);
  const std::string makefile = plan_makefile(p);
  check_work_folder(W, makefile);
  for (const char* d : {"", "jobs", "cache", "geometry", "detect", "tiles", "pairs", "logs"}) create_output_dir((W / d).string());
  for (const PlanJob& j : p.detect) create_output_dir((W / j.target).parent_path().string());
  for (const auto& pr : p.pairs) create_output_dir((W / "tiles" / pair_name(pr)).string());
  write_file_atomic((W / "plan.mk").string(), makefile);
  for (const PlanStage& st : plan_stages(p)) write_file_atomic((W / "jobs" / (st.name + ".jobs")).string(), plan_job_file(*st.jobs));
  write_file_atomic((W / "slurm-array.sbatch").string(), plan_sbatch_script());
  write_file_atomic((W / "submit-slurm.sh").string(), plan_slurm_submit(p, o));
  write_file_atomic((W / "run-parallel.sh").string(), plan_parallel_runner(p, o));
}

}  // namespace tpkit
