#include "tpkit/report/run_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "tpkit/core/coverage_plot.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/residual_field.hpp"
#include "tpkit/core/svg_plot.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/version.hpp"
#include "tpkit/report/report_summary.hpp"

namespace tpkit {

namespace fs = std::filesystem;

namespace {

// The kind of a tpkit table file ("# tpkit KIND VERSION"), "" for anything else (a makefile's comment, an
// image): its first line only, read with a header's bound, so that a large file without a line break in a
// folder is not read whole. (Not open_input_file: a file looked at here is no input of the run unless it
// is a tpkit file; the page may be written into the folder it reports on.)
std::string tpkit_kind(const fs::path& p) {
  constexpr size_t kMaxHeaderLine = 4096;
  std::ifstream in(p, std::ios::binary);
  std::string line;
  try {
    if (!in || !read_text_line(in, line, p.string(), 1, kMaxHeaderLine)) return "";
  } catch (const InputError&) {
    return "";  // binary data, or a first line longer than any header
  }
  return tpkit_header_kind(line);
}

// By kind: tracks and matches through their own readers (nan views allowed), any other kind with
// records as numbers (nan shown as it is written: an empty slope class of a dem-dz file, a check point not
// intersected in an accuracy file) and rows of any length. The input is read once: it may be a pipe.
TextTable read_any(const std::string& path) {
  TextInput in(path);
  const std::string kind = in.header_kind();
  if (kind == "tracks") return read_table(in.stream(), path, tracks_read_options());
  if (kind == "matches") return read_table(in.stream(), path, matches_read_options());
  ReadOptions o;
  o.max_version = 99;
  o.columnar = false;
  o.may_be_missing = [](const std::string&) { return true; };
  return read_table(in.stream(), path, o);
}

// An error for the page: a std::filesystem error in the project's words.
std::string error_text(const std::exception& e) {
  if (const auto* f = dynamic_cast<const fs::filesystem_error*>(&e)) return filesystem_error_message(*f);
  return e.what();
}

std::string esc(const std::string& s) { return svg_escape(s); }

int col(const TextTable& t, const std::string& name) { return t.find(name); }

// Views k = 1.. whose x{k}, y{k} columns exist.
int view_count(const TextTable& t) {
  int k = 0;
  while (col(t, "x" + std::to_string(k + 1)) >= 0 && col(t, "y" + std::to_string(k + 1)) >= 0) ++k;
  return k;
}

std::string image_name(const TextTable& t, int k) {
  return k < static_cast<int>(t.images.size()) ? fs::path(t.images[k].path).filename().string() : "view " + std::to_string(k + 1);
}

std::string coverage_section(const TextTable& t) {
  const int nv = view_count(t);
  std::vector<CoverageView> views;
  for (int k = 0; k < nv; ++k) {
    CoverageView v;
    v.title = image_name(t, k);
    if (k < static_cast<int>(t.images.size())) {
      v.image = t.images[k].path;
      v.width = static_cast<double>(t.images[k].width), v.height = static_cast<double>(t.images[k].height);
    }
    const int cx = col(t, "x" + std::to_string(k + 1)), cy = col(t, "y" + std::to_string(k + 1));
    for (const auto& r : t.rows)
      if (cx < static_cast<int>(r.size()) && cy < static_cast<int>(r.size()) && std::isfinite(r[cx]) && std::isfinite(r[cy]))
        v.x.push_back(r[cx]), v.y.push_back(r[cy]);
    views.push_back(std::move(v));
  }
  if (views.empty()) return "";
  return "<h3>Coverage</h3>\n" + coverage_figure(views, "tie points per cell: " + fs::path(t.source).filename().string()).inline_svg();
}

std::string track_lengths(const TextTable& t) {
  const int nv = view_count(t);
  std::map<int, long> by;
  for (const auto& r : t.rows) {
    int seen = 0;
    for (int k = 0; k < nv; ++k) {
      int cx = col(t, "x" + std::to_string(k + 1));
      seen += cx < static_cast<int>(r.size()) && std::isfinite(r[cx]);
    }
    ++by[seen];
  }
  std::ostringstream o;
  o << "<table><tr><th>views per track</th><th>tracks</th></tr>\n";
  for (const auto& [len, n] : by) o << "<tr><td>" << len << "</td><td>" << n << "</td></tr>\n";
  o << "</table>\n";
  return o.str();
}

// Every record as long as the columns line (the table is read with rows of any length, for kinds
// without a figure): a figure reads its columns by index.
void require_full_records(const TextTable& t) {
  for (size_t k = 0; k < t.rows.size(); ++k)
    if (t.rows[k].size() < t.columns.size())
      throw InputError(t.source, t.row_line[k], std::to_string(t.rows[k].size()) + " fields for " +
                                                    std::to_string(t.columns.size()) + " columns");
}

// reproj-eval's residuals: columns x1..y3, dx1..dy3, check (0 fit, 1 check).
std::string eval_section(const TextTable& t) {
  require_full_records(t);
  const int ck = col(t, "check");
  std::vector<ResidualView> views;
  std::vector<HistogramSet> hist = {{"fit", "#4c78a8", {}}, {"check", "#e45756", {}}};
  bool any_check = false;
  for (const auto& r : t.rows) any_check |= ck >= 0 && r[ck] == 1;
  const int sets = any_check ? 2 : 1;
  for (int set = 0; set < sets; ++set)
    for (int k = 0; k < 3; ++k) {
      ResidualView v;
      v.title = std::string(set ? "check" : (any_check ? "fit" : "tracks")) + ", " + image_name(t, k);
      if (k < static_cast<int>(t.images.size())) v.width = t.images[k].width, v.height = t.images[k].height;
      const std::string s = std::to_string(k + 1);
      const int x = t.require("x" + s), y = t.require("y" + s), dx = t.require("dx" + s), dy = t.require("dy" + s);
      for (const auto& r : t.rows) {
        if ((ck >= 0 && r[ck] == 1) != (set == 1)) continue;
        v.x.push_back(r[x]), v.y.push_back(r[y]), v.dx.push_back(r[dx]), v.dy.push_back(r[dy]);
        hist[set].length.push_back(std::hypot(r[dx], r[dy]));
      }
      views.push_back(std::move(v));
    }
  hist.resize(sets);
  return "<h3>Residual fields (reprojected minus observed)</h3>\n" +
         residual_figure(views, 3, hist, "residuals: " + fs::path(t.source).filename().string()).inline_svg();
}

// rpc-adjust's rpc.residuals: columns image x y dx_before dy_before dx_after dy_after.
std::string rpc_residuals_section(const TextTable& t) {
  const int im = t.require("image"), x = t.require("x"), y = t.require("y");
  const int bx = t.require("dx_before"), by = t.require("dy_before"), ax = t.require("dx_after"), ay = t.require("dy_after");
  require_full_records(t);
  // a pair of panels per image line of the header; an image number that names none of them is refused
  // before anything is drawn (a file saying image 100000 would get 100000 panels)
  const int n = static_cast<int>(t.images.size());
  for (size_t k = 0; k < t.rows.size(); ++k) {
    const double i = t.rows[k][im];
    if (!(i >= 1 && i <= n && i == std::floor(i)))
      throw InputError(t.source, t.row_line[k], "image " + format_id(i) + " is not one of the header's image lines (" +
                                                    (n ? "1 to " + std::to_string(n) : std::string("none")) + ")");
  }
  const int cols = std::min(std::max(n, 1), 4);
  std::vector<ResidualView> grid;
  std::vector<HistogramSet> hist = {{"before", "#bab0ac", {}}, {"after", "#4c78a8", {}}};
  for (int block = 0; block * cols < n; ++block)
    for (int after = 0; after < 2; ++after)
      for (int c = 0; c < cols; ++c) {
        const int i = block * cols + c;  // 0-based; the file's image column is 1-based
        ResidualView v;
        if (i < n) {
          v.title = image_name(t, i) + (after ? ", after" : ", before");
          if (i < static_cast<int>(t.images.size())) v.width = t.images[i].width, v.height = t.images[i].height;
          for (const auto& r : t.rows)
            if (static_cast<int>(r[im]) == i + 1) {
              v.x.push_back(r[x]), v.y.push_back(r[y]);
              v.dx.push_back(after ? r[ax] : r[bx]), v.dy.push_back(after ? r[ay] : r[by]);
              hist[after].length.push_back(std::hypot(v.dx.back(), v.dy.back()));
            }
        }
        grid.push_back(std::move(v));
      }
  return "<h3>Residual fields before and after the adjustment (projected minus observed)</h3>\n" +
         residual_figure(grid, cols, hist, "rpc-adjust residuals: " + fs::path(t.source).filename().string()).inline_svg();
}

std::string table_html(const TextTable& t, size_t max_rows) {
  std::ostringstream o;
  o << "<table><tr>";
  for (const auto& c : t.columns) o << "<th>" << esc(c) << "</th>";
  o << "</tr>\n";
  for (size_t i = 0; i < t.rows.size() && i < max_rows; ++i) {
    o << "<tr>";
    for (double v : t.rows[i]) o << "<td>" << esc(format_figure(v, 6)) << "</td>";
    o << "</tr>\n";
  }
  o << "</table>\n";
  if (t.rows.size() > max_rows) o << "<p>(first " << max_rows << " of " << t.rows.size() << " records)</p>\n";
  return o.str();
}

std::string header_html(const TextTable& t) {
  std::ostringstream o;
  o << "<pre class=\"summary\">";
  if (!t.written_by.empty()) o << "written-by: " << esc(t.written_by) << '\n';
  for (size_t k = 0; k < t.images.size(); ++k)
    o << "image" << k + 1 << ": " << esc(t.images[k].path) << ' ' << t.images[k].width << ' ' << t.images[k].height << '\n';
  for (const auto& [k, v] : t.meta) o << esc(k) << ": " << esc(v) << '\n';
  o << "records: " << t.rows.size() << "</pre>\n";
  return o.str();
}

// A file of the run as read: its table, or why it could not be read.
struct RunFile {
  std::string path;
  TextTable table;
  std::string error;  // "" when read
};

std::string file_section(const RunFile& f, const ReportOptions& opt, bool matches_coverage, std::vector<std::string>& contents) {
  std::ostringstream o;
  const std::string id = "f" + std::to_string(contents.size());
  const std::string& path = f.path;
  if (!f.error.empty()) {
    contents.push_back("<li><a href=\"#" + id + "\">" + esc(path) + "</a> (unreadable)</li>");
    return "<section id=\"" + id + "\"><h2>" + esc(path) + "</h2><p class=\"error\">not read: " + esc(f.error) + "</p></section>\n";
  }
  const TextTable& t = f.table;
  contents.push_back("<li><a href=\"#" + id + "\">" + esc(path) + "</a> (" + esc(t.kind) + ", " + std::to_string(t.rows.size()) +
                     " records)</li>");
  o << "<section id=\"" << id << "\"><h2>" << esc(path) << " <small>" << esc(t.kind) << "</small></h2>\n" << header_html(t);
  try {
    if (t.kind == "matches") {
      o << "<p>" << t.rows.size() << " matches between " << esc(image_name(t, 0)) << " and " << esc(image_name(t, 1)) << "</p>\n";
      if (opt.coverage && matches_coverage) o << coverage_section(t);
    } else if (t.kind == "tracks") {
      o << track_lengths(t);
      if (opt.coverage) o << coverage_section(t);
    } else if (t.kind == "residuals" && col(t, "dx3") >= 0) {
      o << eval_section(t);
    } else if (t.kind == "rpc-residuals") {
      o << rpc_residuals_section(t);
    } else if (t.kind == "rpc-bias") {
      o << table_html(t, 200);
    } else if (t.columns.size() > 0 && t.rows.size() <= 50) {
      o << table_html(t, 50);
    }
  } catch (const std::exception& e) {
    o << "<p class=\"error\">not drawn: " << esc(error_text(e)) << "</p>\n";
  }
  o << "</section>\n";
  return o.str();
}

}  // namespace

std::vector<std::string> report_inputs(const std::vector<std::string>& args) {
  std::vector<std::string> out;
  for (const auto& a : args) {
    if (!fs::exists(a)) throw InputError(a + ": no such file or folder");
    if (!fs::is_directory(a)) {
      out.push_back(a);
      continue;
    }
    std::vector<std::string> found;
    for (auto it = fs::recursive_directory_iterator(a); it != fs::recursive_directory_iterator(); ++it) {
      if (it.depth() >= 3) it.disable_recursion_pending();
      // a tp-plan work folder: its results, not its intermediates (region matches, detection, geometry)
      if (it->is_directory() && fs::exists(it->path().parent_path() / "plan.mk")) {
        const std::string name = it->path().filename().string();
        if (name == "tiles" || name == "detect" || name == "geometry" || name == "cache" || name == "logs") {
          it.disable_recursion_pending();
          continue;
        }
      }
      if (it->is_regular_file() && !tpkit_kind(it->path()).empty()) found.push_back(it->path().string());
    }
    std::sort(found.begin(), found.end());
    out.insert(out.end(), found.begin(), found.end());
  }
  if (out.empty()) throw InputError("no tpkit file found in " + (args.empty() ? std::string("(nothing)") : args.front()));
  return out;
}

std::string run_report_html(const std::vector<std::string>& files, const ReportOptions& opt) {
  // each file read once, first: a pipe cannot be read twice, and the kinds decide what the sections draw
  std::vector<RunFile> run;
  for (const auto& f : files) {
    RunFile r{f, {}, {}};
    try {
      r.table = read_any(f);
    } catch (const std::exception& e) {
      r.error = error_text(e);
    }
    run.push_back(std::move(r));
  }
  std::vector<std::string> contents;
  // counts per pair first; the tracks' coverage covers every image, so a run with tracks draws no
  // coverage per pair
  bool tracks = false;
  std::ostringstream pairs;
  long pair_count = 0;
  for (const auto& r : run) {
    tracks |= r.error.empty() && r.table.kind == "tracks";
    if (!r.error.empty() || r.table.kind != "matches") continue;  // an unreadable file is listed with its error in its own section
    const TextTable& t = r.table;
    if (pair_count++ == 0)
      pairs << "<h2>Matches per pair</h2>\n<table><tr><th>file</th><th>image 1</th><th>image 2</th><th>matches</th><th>refined</th></tr>\n";
    // the share of least-squares positions (refined 1), where the file has the column
    std::string refined = "-";
    if (const int rc = col(t, "refined"); rc >= 0 && !t.rows.empty()) {
      long n = 0;
      for (const auto& row : t.rows) n += rc < static_cast<int>(row.size()) && row[rc] == 1;
      refined = format_figure(100.0 * static_cast<double>(n) / static_cast<double>(t.rows.size()), 3) + "%";
    }
    pairs << "<tr><td>" << esc(r.path) << "</td><td>" << esc(image_name(t, 0)) << "</td><td>" << esc(image_name(t, 1))
          << "</td><td>" << t.rows.size() << "</td><td>" << refined << "</td></tr>\n";
  }
  if (pair_count) pairs << "</table>\n";
  // the run at a glance, then the orthos, before the files one by one
  std::vector<const TextTable*> read;
  for (const auto& r : run)
    if (r.error.empty()) read.push_back(&r.table);
  OrthoOptions oo = opt.orthos;
  for (const TextTable* t : read)
    for (const auto& im : t->images) oo.images.push_back(im.path);
  const std::string glance = run_summary_html(run_summary(read));
  std::string body = orthos_html(opt.orthos_before, opt.orthos_after, oo) + pairs.str();
  for (const auto& r : run) body += file_section(r, opt, !tracks, contents);
  std::ostringstream o;
  o << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" << esc(opt.title) << "</title>\n"
    << "<style>body{font-family:sans-serif;margin:1.5em;color:#222}h2{border-bottom:1px solid #aaa;margin-top:2em}"
       "h2 small{color:#777;font-weight:normal}pre.summary{background:#f6f6f6;padding:.6em;overflow-x:auto;font-size:12px}"
       "table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}"
       ".error{color:#b00}svg{max-width:100%;height:auto;display:block;margin:.5em 0}"
       ".glance{background:#eaf1fa;border:2px solid #4c78a8;border-radius:6px;padding:.2em 1em .8em;margin:1em 0}"
       ".glance h2{border:none;margin:.4em 0}.glance table{font-size:14px}.glance th{text-align:left;background:#d5e3f3}"
       ".glance td{text-align:left;background:#fff}.glance td.src{color:#666;font-size:12px}"
       ".row{display:flex;flex-wrap:wrap;gap:1em;align-items:flex-start}figure.ortho{margin:0}"
       "figure.ortho figcaption{font-size:12px;color:#444}svg.flicker{margin:0}</style></head>\n<body>\n"
    << "<h1>" << esc(opt.title) << "</h1>\n<p>written by " << esc(written_by()) << "; " << files.size() << " files</p>\n" << glance << "<ul>\n";
  for (const auto& c : contents) o << c << '\n';
  o << "</ul>\n" << body << "</body></html>\n";
  return o.str();
}

}  // namespace tpkit
