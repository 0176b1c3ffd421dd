#include "tpkit/report/report_summary.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <cstdlib>

#include "tpkit/core/svg_plot.hpp"

namespace tpkit {

namespace {

std::string file_name(const TextTable& t) { return std::filesystem::path(t.source).filename().string(); }

std::string share(long part, long whole) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f%%", whole > 0 ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0);
  return b;
}

// A header line's value as written ("?" when the line is missing: the page shows what the file says, no more).
std::string written(const TextTable& t, const std::string& key) {
  const std::string v = meta_get(t.meta, key);
  return v.empty() ? "?" : v;
}

// A statistic of a header line for the eye: 3 significant digits ("%.3g"), whole units from 1000 on ("%.0f");
// a value that is not a number as written.
std::string figure(const TextTable& t, const std::string& key) {
  const std::string v = written(t, key);
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (end == v.c_str() || *end) return v;
  char b[48];
  std::snprintf(b, sizeof b, std::fabs(x) >= 1000 ? "%.0f" : "%.3g", x);
  return b;
}

// Views k = 1.. whose x{k} columns exist; a view is seen when its x is a number.
std::map<int, long> by_views(const TextTable& t) {
  std::vector<int> xs;
  for (int k = 1; t.find("x" + std::to_string(k)) >= 0 && t.find("y" + std::to_string(k)) >= 0; ++k) xs.push_back(t.find("x" + std::to_string(k)));
  std::map<int, long> by;
  for (const auto& r : t.rows) {
    int seen = 0;
    for (int c : xs) seen += c < static_cast<int>(r.size()) && std::isfinite(r[c]);
    ++by[seen];
  }
  return by;
}

void matches_line(const std::vector<const TextTable*>& tables, std::vector<SummaryLine>& out) {
  long pairs = 0, total = 0, least = 0, most = 0, refined = 0, with_column = 0;
  for (const TextTable* t : tables) {
    if (t->kind != "matches") continue;
    const long n = static_cast<long>(t->rows.size());
    least = pairs ? std::min(least, n) : n;
    most = pairs ? std::max(most, n) : n;
    ++pairs, total += n;
    const int c = t->find("refined");
    if (c < 0) continue;
    with_column += n;
    for (const auto& r : t->rows) refined += c < static_cast<int>(r.size()) && r[c] == 1;
  }
  if (!pairs) return;
  std::string s = std::to_string(total) + " matches in " + std::to_string(pairs) + (pairs == 1 ? " pair" : " pairs");
  if (pairs > 1) s += " (" + std::to_string(least) + " to " + std::to_string(most) + " per pair)";
  if (with_column) s += ", " + share(refined, with_column) + " refined";
  out.push_back({"matches", pairs == 1 ? "1 file" : std::to_string(pairs) + " files", s, "s-matches"});
}

}  // namespace

std::vector<SummaryLine> run_summary(const std::vector<const TextTable*>& tables) {
  std::vector<SummaryLine> out;
  matches_line(tables, out);
  // one line per file of the other kinds, numbered by kind
  std::map<std::string, int> count;
  auto add = [&](const std::string& key, const std::string& id, const TextTable& t, const std::string& text) {
    out.push_back({key, file_name(t), text, "s-" + id + "-" + std::to_string(++count[id])});
  };
  for (const TextTable* t : tables)
    if (t->kind == "tracks") {
      std::string s = std::to_string(t->rows.size()) + " tracks";
      const auto by = by_views(*t);
      std::string parts;
      for (const auto& [views, n] : by) parts += (parts.empty() ? "" : ", ") + std::to_string(views) + " views: " + std::to_string(n);
      if (!parts.empty()) s += " (" + parts + ")";
      add("tracks", "tracks", *t, s);
    }
  for (const TextTable* t : tables)
    if (t->kind == "rpc-residuals") {
      std::string s = "rms " + figure(*t, "rms_before_px") + " px before, " + figure(*t, "rms_after_px") + " px after";
      if (!meta_get(t->meta, "rms_after_unflagged_px").empty()) s += " (" + figure(*t, "rms_after_unflagged_px") + " px without the flagged tracks)";
      s += ", " + std::to_string(t->rows.size()) + " observations";
      if (!meta_get(t->meta, "check_rms_px").empty())
        s += "; check tracks " + figure(*t, "check_rms_px") + " px over " + written(*t, "check_observations") + " observations";
      add("adjustment", "adjustment", *t, s);
    }
  // the adjustment's flagged tracks; a ground file's flagged points only when no adjustment says it (rpc-adjust
  // writes both, of the same tracks)
  bool flagged_said = false;
  for (const TextTable* t : tables)
    if (t->kind == "rpc-residuals" && !meta_get(t->meta, "flagged_tracks").empty()) {
      const std::string f = meta_get(t->meta, "flagged_tracks"), n = meta_get(t->meta, "tracks");
      std::string s = f + " of " + (n.empty() ? std::string("?") : n) + " tracks";
      const long fl = std::strtol(f.c_str(), nullptr, 10), all = std::strtol(n.c_str(), nullptr, 10);
      if (all > 0) s += " (" + share(fl, all) + ")";
      add("flagged", "flagged", *t, s);
      flagged_said = true;
    }
  for (const TextTable* t : tables)
    if (!flagged_said && t->kind == "ground" && t->find("flagged") >= 0) {
      const int c = t->find("flagged");
      long fl = 0;
      for (const auto& r : t->rows) fl += c < static_cast<int>(r.size()) && r[c] == 1;
      add("flagged", "flagged", *t, std::to_string(fl) + " of " + std::to_string(t->rows.size()) + " ground points (" +
                                        share(fl, static_cast<long>(t->rows.size())) + ")");
    }
  for (const TextTable* t : tables)
    if (t->kind == "accuracy")
      for (const std::string set : {"check", "control"}) {
        if (meta_get(t->meta, set + "_after_n").empty()) continue;
        const std::string b = set + "_before_", a = set + "_after_";
        add(set + " points", set, *t,
            written(*t, a + "n") + " " + set + " points: horizontal rmse " + figure(*t, b + "rmse_h_m") + " m before, " +
                figure(*t, a + "rmse_h_m") + " m after; vertical " + figure(*t, b + "rmse_v_m") + " m before, " +
                figure(*t, a + "rmse_v_m") + " m after");
      }
  for (const TextTable* t : tables)
    if (t->kind == "residuals" && !meta_get(t->meta, "rmse_px").empty()) {
      std::string s = "rmse " + figure(*t, "rmse_px") + " px over " + written(*t, "n") + " tracks";
      if (!meta_get(t->meta, "check_rmse_px").empty())
        s += "; held-out check " + figure(*t, "check_rmse_px") + " px over " + written(*t, "check_n") + " tracks";
      add("trifocal fit", "fit", *t, s);
    }
  return out;
}

std::string run_summary_html(const std::vector<SummaryLine>& lines) {
  if (lines.empty()) return "";
  std::string o = "<section id=\"summary\" class=\"glance\"><h2>At a glance</h2>\n<table>\n";
  for (const auto& l : lines)
    o += "<tr><th>" + svg_escape(l.key) + "</th><td id=\"" + l.id + "\">" + svg_escape(l.text) + "</td><td class=\"src\">" +
         svg_escape(l.source) + "</td></tr>\n";
  return o + "</table></section>\n";
}

}  // namespace tpkit
