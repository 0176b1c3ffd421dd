#include "tpkit/tracks_chain.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <numeric>
#include <unordered_map>

#include "tpkit/error.hpp"

namespace tpkit {

namespace {
struct UnionFind {
  std::vector<size_t> p;
  size_t add() {
    p.push_back(p.size());
    return p.size() - 1;
  }
  size_t find(size_t a) {
    while (p[a] != a) a = p[a] = p[p[a]];
    return a;
  }
  void unite(size_t a, size_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (b < a) std::swap(a, b);
    p[b] = a;  // smallest index as root: deterministic
  }
};

std::string canonical(const std::string& p) {
  std::error_code ec;
  auto c = std::filesystem::weakly_canonical(p, ec);
  return ec ? p : c.string();
}

struct Node {
  int image;
  long long id;
  double x, y;  // keypoint position
};
struct Link {
  size_t u, v;    // nodes: u in the file's image 1, v in its image 2
  double x2, y2;  // refined position of v's ground point (relative to u's keypoint)
};
}  // namespace

Tracks chain_tracks(const std::vector<Matches>& files, const ChainOptions& o, ChainStats* stats) {
  ChainStats st;
  // images: given order first, then order of first appearance
  std::vector<ImageRef> imgs;
  std::vector<std::string> canon;
  auto image_index = [&](const ImageRef& r, bool add) -> int {
    for (size_t i = 0; i < imgs.size(); ++i)
      if (imgs[i].path == r.path) return static_cast<int>(i);
    std::string c = canonical(r.path);
    for (size_t i = 0; i < imgs.size(); ++i)
      if (canon[i] == c) return static_cast<int>(i);
    if (!add) return -1;
    imgs.push_back(r);
    canon.push_back(c);
    return static_cast<int>(imgs.size() - 1);
  };
  for (const auto& p : o.images) image_index(ImageRef{p, 0, 0}, true);
  const size_t given = o.images.size();
  std::vector<char> seen(given, 0);
  for (const auto& m : files) {
    if (m.image1.path.empty() || m.image2.path.empty())
      throw InputError(m.source, 0, "matches file without image1/image2 header lines: tp-chain needs them to join files");
    for (const ImageRef* r : {&m.image1, &m.image2}) {
      int k = image_index(*r, true);
      if (k < static_cast<int>(given)) {
        seen[k] = 1;
        if (imgs[k].width == 0) {
          imgs[k].width = r->width;
          imgs[k].height = r->height;
        }
      }
    }
  }
  for (size_t k = 0; k < given; ++k)
    if (!seen[k]) throw InputError(o.images[k], 0, "image given with --images appears in no matches file");
  const int K = given ? static_cast<int>(given) : static_cast<int>(imgs.size());
  if (o.min_views < 2) throw UsageError("--min-views must be at least 2");
  if (o.min_views > K)
    throw UsageError("--min-views " + std::to_string(o.min_views) + " is more than the " + std::to_string(K) + " images");

  // nodes and links
  std::vector<Node> nodes;
  std::unordered_map<long long, size_t> node_of_key;  // per image: separate maps
  std::vector<std::unordered_map<long long, size_t>> node_of(imgs.size());
  UnionFind uf;
  std::vector<Link> links;
  auto node = [&](int img, long long id, double x, double y) {
    auto it = node_of[img].find(id);
    if (it != node_of[img].end()) return it->second;
    size_t n = uf.add();
    nodes.push_back({img, id, x, y});
    node_of[img].emplace(id, n);
    return n;
  };
  for (const auto& m : files) {
    int a = image_index(m.image1, false), b = image_index(m.image2, false);
    if (a == b) throw InputError(m.source, 0, "both images of the file are the same image");
    int ckx = m.extra.find("kx2"), cky = m.extra.find("ky2");
    for (size_t r = 0; r < m.size(); ++r) {
      double kx = ckx >= 0 ? m.extra.values(r, ckx) : m.xy(r, 2);
      double ky = cky >= 0 ? m.extra.values(r, cky) : m.xy(r, 3);
      size_t u = node(a, m.id1[r], m.xy(r, 0), m.xy(r, 1));
      size_t v = node(b, m.id2[r], kx, ky);
      links.push_back({u, v, m.xy(r, 2), m.xy(r, 3)});
      uf.unite(u, v);
    }
  }
  // same-position keypoints of one image are one point
  for (size_t img = 0; img < imgs.size(); ++img) {
    std::vector<size_t> ns;
    for (const auto& kv : node_of[img]) ns.push_back(kv.second);
    std::sort(ns.begin(), ns.end(), [&](size_t p, size_t q) {
      if (nodes[p].x != nodes[q].x) return nodes[p].x < nodes[q].x;
      if (nodes[p].y != nodes[q].y) return nodes[p].y < nodes[q].y;
      return p < q;
    });
    for (size_t i = 0; i < ns.size(); ++i)
      for (size_t j = i + 1; j < ns.size() && nodes[ns[j]].x - nodes[ns[i]].x <= o.same_position; ++j)
        if (std::abs(nodes[ns[j]].y - nodes[ns[i]].y) <= o.same_position && uf.find(ns[i]) != uf.find(ns[j])) {
          uf.unite(ns[i], ns[j]);
          ++st.merged_duplicates;
        }
  }
  // components
  std::vector<std::vector<size_t>> adj(nodes.size());
  for (size_t l = 0; l < links.size(); ++l) {
    adj[links[l].u].push_back(l);
    adj[links[l].v].push_back(l);
  }
  std::unordered_map<size_t, std::vector<size_t>> comp;
  for (size_t n = 0; n < nodes.size(); ++n) comp[uf.find(n)].push_back(n);
  st.components = static_cast<long>(comp.size());
  // image order rank (output images first)
  std::vector<int> rank(imgs.size());
  std::iota(rank.begin(), rank.end(), 0);

  struct Out {
    long long ref_id;
    std::vector<double> xy;
  };
  std::vector<Out> out;
  auto same = [&](size_t p, size_t q) {
    return std::abs(nodes[p].x - nodes[q].x) <= o.same_position && std::abs(nodes[p].y - nodes[q].y) <= o.same_position;
  };
  for (auto& kv : comp) {
    auto& ns = kv.second;
    std::sort(ns.begin(), ns.end(), [&](size_t p, size_t q) {
      if (nodes[p].image != nodes[q].image) return nodes[p].image < nodes[q].image;
      return nodes[p].id < nodes[q].id;
    });
    // per image: conflicting (two different positions)?
    std::vector<char> present(imgs.size(), 0), conflict(imgs.size(), 0);
    std::vector<size_t> first(imgs.size(), 0);
    for (size_t n : ns) {
      int im = nodes[n].image;
      if (!present[im]) {
        present[im] = 1;
        first[im] = n;
      } else if (!same(first[im], n)) {
        conflict[im] = 1;
      }
    }
    int ref = -1;
    for (size_t im = 0; im < imgs.size(); ++im)
      if (present[im]) {
        ref = static_cast<int>(im);
        break;
      }
    if (conflict[ref]) {
      ++st.dropped_reference_conflicts;
      continue;
    }
    for (size_t im = 0; im < imgs.size(); ++im)
      if (conflict[im]) ++st.views_dropped_conflicts;
    // breadth first from the reference keypoint(s)
    std::unordered_map<size_t, Eigen::Vector2d> pos;
    std::deque<size_t> q;
    for (size_t n : ns)
      if (nodes[n].image == ref) {
        pos[n] = {nodes[n].x, nodes[n].y};
        q.push_back(n);
      }
    std::vector<char> have(imgs.size(), 0);
    std::vector<Eigen::Vector2d> view(imgs.size());
    have[ref] = 1;
    view[ref] = {nodes[first[ref]].x, nodes[first[ref]].y};
    while (!q.empty()) {
      size_t n = q.front();
      q.pop_front();
      const Eigen::Vector2d pn = pos[n];
      for (size_t l : adj[n]) {
        const Link& L = links[l];
        size_t m = L.u == n ? L.v : L.u;
        int im = nodes[m].image;
        if (conflict[im] || pos.count(m)) continue;
        Eigen::Vector2d pm;
        if (L.u == n)  // forward: refined position in image 2, moved by n's offset from its keypoint
          pm = Eigen::Vector2d(L.x2, L.y2) + (pn - Eigen::Vector2d(nodes[n].x, nodes[n].y));
        else  // reversed: L.x2 is n's refined position relative to m's keypoint
          pm = Eigen::Vector2d(nodes[m].x, nodes[m].y) - (Eigen::Vector2d(L.x2, L.y2) - pn);
        pos[m] = pm;
        q.push_back(m);
        if (!have[im]) {
          have[im] = 1;
          view[im] = pm;
        }
      }
    }
    int views = 0;
    for (int im = 0; im < K; ++im) views += have[im];
    if (views >= 2) st.by_length[views]++;
    if (views < K || views < o.min_views) continue;
    Out t;
    t.ref_id = nodes[first[ref]].id;
    for (int im = 0; im < K; ++im) {
      t.xy.push_back(view[im].x());
      t.xy.push_back(view[im].y());
    }
    out.push_back(std::move(t));
  }
  std::sort(out.begin(), out.end(), [](const Out& a, const Out& b) { return a.ref_id < b.ref_id; });
  Tracks T;
  T.images.assign(imgs.begin(), imgs.begin() + K);
  T.xy.resize(static_cast<Eigen::Index>(out.size()), 2 * K);
  T.extra.names = {"kp1"};
  T.extra.values.resize(static_cast<Eigen::Index>(out.size()), 1);
  for (size_t i = 0; i < out.size(); ++i) {
    T.id.push_back(static_cast<long long>(i));
    for (int c = 0; c < 2 * K; ++c) T.xy(static_cast<Eigen::Index>(i), c) = out[i].xy[c];
    T.extra.values(static_cast<Eigen::Index>(i), 0) = static_cast<double>(out[i].ref_id);
  }
  st.written = static_cast<long>(out.size());
  meta_set(T.meta, "positions", "refer to the keypoint of image1 (kp1 = its id in image1's matches files)");
  meta_set(T.meta, "min_views", std::to_string(o.min_views));
  if (stats) *stats = st;
  return T;
}

}  // namespace tpkit
