#include "tpkit/match/matches_merge.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {

struct Candidate {
  long long id1, id2;
  size_t file;
  Eigen::Index row;
  double inner;  // distance of x1 inside its file's region, pixels
};

// Distance from (x, y) to the border of the file's region (x0 y0 w h in the `region` metadata), or
// infinity for a file without one.
struct RegionBorder {
  bool whole = true;
  double x0 = 0, y0 = 0, w = 0, h = 0;
  explicit RegionBorder(const Matches& m) {
    const std::string r = meta_get(m.meta, "region");
    if (r.empty()) return;
    std::istringstream in(r);
    if (!(in >> x0 >> y0 >> w >> h)) throw InputError(m.source, 0, "unreadable region metadata: " + r);
    // a region that holds no pixel (tp-match --region writes W, H > 0) would rank every record of its file
    // as outside it
    if (!(w > 0 && h > 0) || !std::isfinite(x0 + y0 + w + h))
      throw InputError(m.source, 0, "region metadata " + r.substr(0, r.find(" (")) +
                                        ": not a window of pixels (x0 y0 width height, width and height > 0)");
    whole = false;
  }
  double inner(double x, double y) const {
    if (whole) return std::numeric_limits<double>::infinity();
    return std::min({x - (x0 - 0.5), x0 + w - 0.5 - x, y - (y0 - 0.5), y0 + h - 0.5 - y});
  }
};

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

// Every record of every file, then groups by sorting (stable: a group keeps the files' order, so that the
// earlier file wins ties): one record per match, then per id1, then per id2.
Matches merge_matches(const std::vector<Matches>& files, MergeStats* stats, const MergeOptions& o) {
  if (files.empty()) throw UsageError("no matches file to merge");
  MergeStats st;
  st.files = static_cast<long>(files.size());
  const Matches& first = files[0];
  // every list at its size from the start: grown by doubling, the 1.14 million candidates of a 10000²
  // pair's 16 regions were copied and their pages faulted again at each step (a fifth of the merge's time)
  size_t total = 0;
  for (const Matches& m : files) total += m.size();
  std::vector<Candidate> all;
  all.reserve(total);
  for (size_t f = 0; f < files.size(); ++f) {
    const Matches& m = files[f];
    check_same_pair(first, m);
    const RegionBorder region(m);
    for (Eigen::Index k = 0; k < m.xy.rows(); ++k)
      all.push_back({m.id1[static_cast<size_t>(k)], m.id2[static_cast<size_t>(k)], f, k, region.inner(m.xy(k, 0), m.xy(k, 1))});
  }
  st.records = static_cast<long>(all.size());
  // the best of each run of equal keys (the first on ties), in the order of `v`
  auto best_of_runs = [&](std::vector<Candidate>& v, auto same_key, auto on_repeat) {
    std::vector<Candidate> kept;
    kept.reserve(v.size());  // at most one a record; pages past those written are never touched
    for (size_t a = 0, b; a < v.size(); a = b) {
      Candidate best = v[a];
      for (b = a + 1; b < v.size() && same_key(v[a], v[b]); ++b) {
        on_repeat(best, v[b]);
        if (better(v[b], best)) best = v[b];
      }
      kept.push_back(best);
    }
    v.swap(kept);
  };
  auto by_match = [](const Candidate& p, const Candidate& q) { return p.id1 != q.id1 ? p.id1 < q.id1 : p.id2 < q.id2; };
  std::stable_sort(all.begin(), all.end(), by_match);
  // one match at two positions is a conflict: one of them is wrong
  best_of_runs(
      all, [](const Candidate& p, const Candidate& q) { return p.id1 == q.id1 && p.id2 == q.id2; },
      [&](const Candidate& kept, const Candidate& c) {
        const double apart = (files[kept.file].xy.row(kept.row) - files[c.file].xy.row(c.row)).cwiseAbs().maxCoeff();
        ++(apart > o.same_position ? st.conflicts : st.duplicates);
      });
  // conflicts: one record per id1, then one per id2
  auto count_conflict = [&](const Candidate&, const Candidate&) { ++st.conflicts; };
  best_of_runs(all, [](const Candidate& p, const Candidate& q) { return p.id1 == q.id1; }, count_conflict);
  std::stable_sort(all.begin(), all.end(), [](const Candidate& p, const Candidate& q) { return p.id2 < q.id2; });
  best_of_runs(all, [](const Candidate& p, const Candidate& q) { return p.id2 == q.id2; }, count_conflict);
  std::sort(all.begin(), all.end(), by_match);

  Matches out;
  out.image1 = first.image1;
  out.image2 = first.image2;
  for (const auto& kv : first.meta)
    if (kv.first != "region" && kv.first != "region-read" && kv.first != "keypoints" && kv.first != "putative" &&
        kv.first != "verified")
      out.meta.push_back(kv);
  out.extra.names = first.extra.names;
  const auto n = static_cast<Eigen::Index>(all.size());
  out.xy.resize(n, 4);
  out.extra.values.resize(n, static_cast<Eigen::Index>(first.extra.names.size()));
  out.id1.reserve(all.size());
  out.id2.reserve(all.size());
  Eigen::Index r = 0;
  for (const Candidate& c : all) {  // sorted by (id1, id2)
    const Matches& m = files[c.file];
    out.id1.push_back(c.id1);
    out.id2.push_back(c.id2);
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
