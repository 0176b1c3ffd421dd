#include "tpkit/core/table_sample.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <random>

#include "tpkit/core/error.hpp"

namespace tpkit {

SampleResult sample_records(const TextTable& t, const SampleOptions& opt) {
  std::vector<size_t> pool;
  int cx = -1, cy = -1;
  if (opt.box || opt.spread) {
    std::string v = std::to_string(opt.box_view);
    cx = t.find("x" + v);
    cy = t.find("y" + v);
    if (cx < 0 && t.kind != "tracks" && t.kind != "matches") {  // points: columns x y
      cx = t.find("x");
      cy = t.find("y");
    }
    if (cx < 0 || cy < 0) throw UsageError(t.source + ": no columns x" + v + " y" + v + " to select by position");
  }
  for (size_t r = 0; r < t.rows.size(); ++r) {
    if (opt.box) {
      const auto& b = *opt.box;
      double x = t.rows[r][cx], y = t.rows[r][cy];
      if (x < b[0] || x > b[2] || y < b[1] || y > b[3]) continue;
    }
    pool.push_back(r);
  }
  SampleResult res;
  size_t n = opt.n < 0 ? pool.size() : static_cast<size_t>(opt.n);
  if (n > pool.size())
    throw UsageError("asked for " + std::to_string(n) + " records, " + t.source + " has " + std::to_string(pool.size()) +
                     (opt.box ? " inside the box" : ""));
  std::mt19937_64 rng(opt.seed);
  std::vector<size_t> order = pool;
  if (!opt.spread) {
    // partial Fisher-Yates with our own index draw (std::uniform_int_distribution differs between libraries)
    for (size_t i = 0; i < n && i + 1 < order.size(); ++i) {
      size_t j = i + static_cast<size_t>(rng() % (order.size() - i));
      std::swap(order[i], order[j]);
    }
  } else {
    // grid of about n cells over the bounding box of the pool; one record per cell per round
    double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
    for (size_t r : pool) {
      x0 = std::min(x0, t.rows[r][cx]);
      x1 = std::max(x1, t.rows[r][cx]);
      y0 = std::min(y0, t.rows[r][cy]);
      y1 = std::max(y1, t.rows[r][cy]);
    }
    int g = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(std::max<size_t>(n, 1))))));
    std::map<int, std::vector<size_t>> cells;
    for (size_t r : pool) {
      int gx = std::min(g - 1, static_cast<int>((t.rows[r][cx] - x0) / std::max(1e-9, x1 - x0) * g));
      int gy = std::min(g - 1, static_cast<int>((t.rows[r][cy] - y0) / std::max(1e-9, y1 - y0) * g));
      cells[gy * g + gx].push_back(r);
    }
    std::vector<std::vector<size_t>> lists;
    for (auto& kv : cells) {
      auto& v = kv.second;
      for (size_t i = 0; i + 1 < v.size(); ++i) std::swap(v[i], v[i + static_cast<size_t>(rng() % (v.size() - i))]);
      lists.push_back(v);
    }
    for (size_t i = 0; i + 1 < lists.size(); ++i) std::swap(lists[i], lists[i + static_cast<size_t>(rng() % (lists.size() - i))]);
    order.clear();
    for (size_t round = 0; order.size() < pool.size(); ++round)
      for (auto& l : lists)
        if (round < l.size()) order.push_back(l[round]);
  }
  res.drawn.assign(order.begin(), order.begin() + static_cast<long>(n));
  res.rest.assign(order.begin() + static_cast<long>(n), order.end());
  std::sort(res.drawn.begin(), res.drawn.end());
  std::sort(res.rest.begin(), res.rest.end());
  return res;
}

void write_table_subset(std::ostream& os, const TextTable& t, const std::vector<size_t>& rows, const Meta& extra_meta) {
  Meta meta = t.meta;
  for (const auto& kv : extra_meta) meta_set(meta, kv.first, kv.second);
  write_header(os, t.kind.empty() ? "points" : t.kind, t.version > 0 ? t.version : 1, t.images, meta, t.columns);
  for (size_t r : rows) write_record(os, t.rows[r]);
}

}  // namespace tpkit
