#include "tpkit/match/matches_merge.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {

struct Candidate {
  size_t file;
  Eigen::Index row;
  double inner;  // distance of x1 inside its file's region, pixels
};

// Distance from (x, y) to the border of the file's region (x0 y0 w h in the `region` metadata), or
// infinity for a file without one.
double inner_distance(const Matches& m, double x, double y) {
  const std::string r = meta_get(m.meta, "region");
  if (r.empty()) return std::numeric_limits<double>::infinity();
  std::istringstream in(r);
  double x0, y0, w, h;
  if (!(in >> x0 >> y0 >> w >> h)) throw InputError(m.source, 0, "unreadable region metadata: " + r);
  return std::min({x - (x0 - 0.5), x0 + w - 0.5 - x, y - (y0 - 0.5), y0 + h - 0.5 - y});
}

void check_same_pair(const Matches& first, const Matches& m) {
  auto same = [](const ImageRef& p, const ImageRef& q) { return p.path == q.path && p.width == q.width && p.height == q.height; };
  if (!same(first.image1, m.image1) || !same(first.image2, m.image2))
    throw InputError(m.source, 0, "is a matches file of " + m.image1.path + " and " + m.image2.path + ", not of " +
                                      first.image1.path + " and " + first.image2.path + " (" + first.source + ")");
  for (const char* k : {"detector1", "detector2"})
    if (meta_get(first.meta, k) != meta_get(m.meta, k))
      throw InputError(m.source, 0, std::string(k) + " differs from " + first.source + "'s: keypoint ids of other detector options do not join");
  if (first.extra.names != m.extra.names) throw InputError(m.source, 0, "its columns differ from those of " + first.source);
}

// Best candidate of a group: largest inner distance, then earliest file and row.
bool better(const Candidate& p, const Candidate& q) {
  if (p.inner != q.inner) return p.inner > q.inner;
  if (p.file != q.file) return p.file < q.file;
  return p.row < q.row;
}

}  // namespace

Matches merge_matches(const std::vector<Matches>& files, MergeStats* stats, const MergeOptions& o) {
  if (files.empty()) throw UsageError("no matches file to merge");
  MergeStats st;
  st.files = static_cast<long>(files.size());
  const Matches& first = files[0];
  std::map<std::pair<long long, long long>, Candidate> by_match;
  for (size_t f = 0; f < files.size(); ++f) {
    const Matches& m = files[f];
    check_same_pair(first, m);
    for (Eigen::Index k = 0; k < m.xy.rows(); ++k) {
      ++st.records;
      const Candidate c{f, k, inner_distance(m, m.xy(k, 0), m.xy(k, 1))};
      const auto key = std::make_pair(m.id1[static_cast<size_t>(k)], m.id2[static_cast<size_t>(k)]);
      auto [it, fresh] = by_match.emplace(key, c);
      if (!fresh) {
        // one match at two positions is a conflict: one of them is wrong
        const Matches& kept = files[it->second.file];
        const double apart = (kept.xy.row(it->second.row) - m.xy.row(k)).cwiseAbs().maxCoeff();
        ++(apart > o.same_position ? st.conflicts : st.duplicates);
        if (better(c, it->second)) it->second = c;
      }
    }
  }
  // conflicts: one record per id1, then one per id2
  auto keep_one_per = [&](auto key_of) {
    std::map<long long, std::pair<std::pair<long long, long long>, Candidate>> best;
    for (const auto& [match, c] : by_match) {
      auto [it, fresh] = best.emplace(key_of(match), std::make_pair(match, c));
      if (!fresh) {
        ++st.conflicts;
        if (better(c, it->second.second)) it->second = {match, c};
      }
    }
    std::map<std::pair<long long, long long>, Candidate> kept;
    for (const auto& [k, mc] : best) kept.emplace(mc.first, mc.second);
    by_match.swap(kept);
  };
  keep_one_per([](const std::pair<long long, long long>& m) { return m.first; });
  keep_one_per([](const std::pair<long long, long long>& m) { return m.second; });

  Matches out;
  out.image1 = first.image1;
  out.image2 = first.image2;
  for (const auto& kv : first.meta)
    if (kv.first != "region" && kv.first != "region-read" && kv.first != "keypoints" && kv.first != "putative" &&
        kv.first != "verified")
      out.meta.push_back(kv);
  out.extra.names = first.extra.names;
  const auto n = static_cast<Eigen::Index>(by_match.size());
  out.xy.resize(n, 4);
  out.extra.values.resize(n, static_cast<Eigen::Index>(first.extra.names.size()));
  Eigen::Index r = 0;
  for (const auto& [match, c] : by_match) {  // sorted by (id1, id2)
    const Matches& m = files[c.file];
    out.id1.push_back(match.first);
    out.id2.push_back(match.second);
    out.xy.row(r) = m.xy.row(c.row);
    if (out.extra.values.cols() > 0) out.extra.values.row(r) = m.extra.values.row(c.row);
    ++r;
  }
  st.written = static_cast<long>(n);
  meta_set(out.meta, "merged", std::to_string(st.files) + " files, " + std::to_string(st.records) + " records: " +
                                   std::to_string(st.duplicates) + " duplicates, " + std::to_string(st.conflicts) +
                                   " conflicts dropped, " + std::to_string(st.written) + " written");
  if (stats) *stats = st;
  return out;
}

}  // namespace tpkit
