#include "tpkit/match/tracks_chain.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <unordered_map>

#include "tpkit/core/error.hpp"

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
  UnionFind uf;
  std::vector<Link> links;
  std::vector<std::unordered_map<long long, size_t>> node_of(imgs.size());  // per image: id -> node
  {
    std::vector<size_t> records(imgs.size(), 0);
    size_t total = 0;
    for (const auto& m : files) {
      records[static_cast<size_t>(image_index(m.image1, false))] += m.size();
      records[static_cast<size_t>(image_index(m.image2, false))] += m.size();
      total += m.size();
    }
    for (size_t i = 0; i < imgs.size(); ++i) node_of[i].reserve(records[i]);
    nodes.reserve(2 * total);
    links.reserve(total);
    uf.p.reserve(2 * total);
  }
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
  std::vector<std::unordered_map<long long, size_t>>().swap(node_of);  // not needed past here: memory back
  // same-position keypoints of one image are one point: every pair (p, q) of one image with
  // |x_q - x_p| <= same_position and |y_q - y_p| <= same_position is joined. A sweep in x order with the
  // window of the points within same_position in x, searched by y: O(n log n + pairs found) per image
  // (the plain window scan was O(n * points in a same_position-wide strip), quadratic on a grid).
  std::vector<std::vector<size_t>> by_image(imgs.size());
  for (size_t n = 0; n < nodes.size(); ++n) by_image[static_cast<size_t>(nodes[n].image)].push_back(n);
  const double sp = o.same_position;
  auto join = [&](size_t p, size_t q) {
    if (uf.find(p) != uf.find(q)) {
      uf.unite(p, q);
      ++st.merged_duplicates;
    }
  };
  for (size_t img = 0; img < imgs.size(); ++img) {
    std::vector<size_t>& ns = by_image[img];
    std::sort(ns.begin(), ns.end(), [&](size_t p, size_t q) {
      if (nodes[p].x != nodes[q].x) return nodes[p].x < nodes[q].x;
      if (nodes[p].y != nodes[q].y) return nodes[p].y < nodes[q].y;
      return p < q;
    });
    // Keypoints at exactly the same position: joined to the first of them, which stands for them all
    // below (the test depends on the coordinates only).
    std::vector<size_t> rep;
    rep.reserve(ns.size());
    for (size_t i = 0; i < ns.size(); ++i) {
      if (!rep.empty() && nodes[ns[i]].x == nodes[rep.back()].x && nodes[ns[i]].y == nodes[rep.back()].y)
        join(rep.back(), ns[i]);
      else
        rep.push_back(ns[i]);
    }
    // For the j-th point (x order) the points before it with x_j - x_i <= sp form a suffix [lo, j) of
    // the order (the rounded difference is monotonic); those with |y_j - y_i| <= sp an interval in y.
    // Small windows are scanned; large ones (many points in one same_position-wide strip, e.g. a grid)
    // are kept in a set ordered by y (entered above 2T points, left below T: amortized O(log n)).
    constexpr size_t T = 32;
    std::set<std::pair<double, size_t>> act;  // (y, index into rep) of the window, in set mode
    bool use_set = false;
    size_t lo = 0;
    for (size_t j = 0; j < rep.size(); ++j) {
      const Node& nj = nodes[rep[j]];
      while (nj.x - nodes[rep[lo]].x > sp) {
        if (use_set) act.erase({nodes[rep[lo]].y, lo});
        ++lo;
      }
      const size_t w = j - lo;
      if (use_set && w < T) {
        act.clear();
        use_set = false;
      } else if (!use_set && w > 2 * T) {
        for (size_t i = lo; i < j; ++i) act.emplace(nodes[rep[i]].y, i);
        use_set = true;
      }
      if (!use_set) {
        for (size_t i = lo; i < j; ++i)
          if (std::abs(nj.y - nodes[rep[i]].y) <= sp) join(rep[i], rep[j]);
      } else {
        auto it = act.lower_bound({nj.y, 0});
        for (auto u = it; u != act.end() && u->first - nj.y <= sp; ++u) join(rep[u->second], rep[j]);
        for (auto d = it; d != act.begin();) {
          --d;
          if (nj.y - d->first > sp) break;
          join(rep[d->second], rep[j]);
        }
        act.emplace(nj.y, j);
      }
    }
  }
  by_image.clear();
  by_image.shrink_to_fit();
  // links of each node, in link order (compressed rows)
  std::vector<size_t> adj_at(nodes.size() + 1, 0), adj;
  for (const Link& L : links) ++adj_at[L.u + 1], ++adj_at[L.v + 1];
  for (size_t n = 0; n < nodes.size(); ++n) adj_at[n + 1] += adj_at[n];
  adj.resize(adj_at[nodes.size()]);
  {
    std::vector<size_t> fill(adj_at.begin(), adj_at.end() - 1);
    for (size_t l = 0; l < links.size(); ++l) {
      adj[fill[links[l].u]++] = l;
      adj[fill[links[l].v]++] = l;
    }
  }
  // components: nodes grouped by root (compressed rows; the output order does not depend on the
  // order of the components, see the sort below)
  std::vector<size_t> root(nodes.size()), comp_at(nodes.size() + 1, 0), comp_nodes(nodes.size());
  for (size_t n = 0; n < nodes.size(); ++n) {
    root[n] = uf.find(n);
    ++comp_at[root[n] + 1];
  }
  for (size_t n = 0; n < nodes.size(); ++n) {
    if (comp_at[n + 1] > 0) ++st.components;
    comp_at[n + 1] += comp_at[n];
  }
  {
    std::vector<size_t> fill(comp_at.begin(), comp_at.end() - 1);
    for (size_t n = 0; n < nodes.size(); ++n) comp_nodes[fill[root[n]]++] = n;
  }
  std::vector<size_t>().swap(root);
  std::vector<size_t>().swap(uf.p);

  // the tracks found: reference keypoint ids and their 2K coordinates, flat (one block, not one per track)
  std::vector<long long> out_ref;
  std::vector<double> out_xy;
  auto same = [&](size_t p, size_t q) {
    return std::abs(nodes[p].x - nodes[q].x) <= o.same_position && std::abs(nodes[p].y - nodes[q].y) <= o.same_position;
  };
  // per-component scratch: reset per component (O(images)) or marked by the component's stamp
  std::vector<char> present(imgs.size()), conflict(imgs.size()), have(imgs.size());
  std::vector<size_t> first(imgs.size());
  std::vector<Eigen::Vector2d> view(imgs.size());
  std::vector<Eigen::Vector2d> pos(nodes.size());
  std::vector<size_t> reached(nodes.size(), 0);  // stamp of the component whose search reached the node
  std::vector<size_t> q;
  q.reserve(64);
  size_t stamp = 0;
  for (size_t rt = 0; rt < nodes.size(); ++rt) {
    if (comp_at[rt + 1] == comp_at[rt]) continue;
    ++stamp;
    auto nb = comp_nodes.begin() + static_cast<std::ptrdiff_t>(comp_at[rt]);
    auto ne = comp_nodes.begin() + static_cast<std::ptrdiff_t>(comp_at[rt + 1]);
    std::sort(nb, ne, [&](size_t p, size_t r) {
      if (nodes[p].image != nodes[r].image) return nodes[p].image < nodes[r].image;
      return nodes[p].id < nodes[r].id;
    });
    // per image: conflicting (two different positions)?
    std::fill(present.begin(), present.end(), 0);
    std::fill(conflict.begin(), conflict.end(), 0);
    std::fill(first.begin(), first.end(), 0);
    for (auto it = nb; it != ne; ++it) {
      size_t n = *it;
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
    q.clear();
    for (auto it = nb; it != ne; ++it)
      if (nodes[*it].image == ref) {
        pos[*it] = {nodes[*it].x, nodes[*it].y};
        reached[*it] = stamp;
        q.push_back(*it);
      }
    std::fill(have.begin(), have.end(), 0);
    std::fill(view.begin(), view.end(), Eigen::Vector2d::Zero());
    have[ref] = 1;
    view[ref] = {nodes[first[ref]].x, nodes[first[ref]].y};
    for (size_t head = 0; head < q.size(); ++head) {
      size_t n = q[head];
      const Eigen::Vector2d pn = pos[n];
      for (size_t a = adj_at[n]; a < adj_at[n + 1]; ++a) {
        const Link& L = links[adj[a]];
        size_t m = L.u == n ? L.v : L.u;
        int im = nodes[m].image;
        if (conflict[im] || reached[m] == stamp) continue;
        Eigen::Vector2d pm;
        if (L.u == n)  // forward: refined position in image 2, moved by n's offset from its keypoint
          pm = Eigen::Vector2d(L.x2, L.y2) + (pn - Eigen::Vector2d(nodes[n].x, nodes[n].y));
        else  // reversed: L.x2 is n's refined position relative to m's keypoint
          pm = Eigen::Vector2d(nodes[m].x, nodes[m].y) - (Eigen::Vector2d(L.x2, L.y2) - pn);
        pos[m] = pm;
        reached[m] = stamp;
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
    out_ref.push_back(nodes[first[ref]].id);
    for (int im = 0; im < K; ++im) {
      out_xy.push_back(view[im].x());
      out_xy.push_back(view[im].y());
    }
  }
  // Written tracks hold every output image, so their reference is image 0 and their reference ids
  // (keypoint ids of image 0, one node each) are distinct: the order is total.
  std::vector<size_t> order(out_ref.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return out_ref[a] < out_ref[b]; });
  Tracks T;
  T.images.assign(imgs.begin(), imgs.begin() + K);
  T.xy.resize(static_cast<Eigen::Index>(order.size()), 2 * K);
  T.extra.names = {"kp1"};
  T.extra.values.resize(static_cast<Eigen::Index>(order.size()), 1);
  T.id.reserve(order.size());
  for (size_t i = 0; i < order.size(); ++i) {
    T.id.push_back(static_cast<long long>(i));
    for (int c = 0; c < 2 * K; ++c) T.xy(static_cast<Eigen::Index>(i), c) = out_xy[order[i] * static_cast<size_t>(2 * K) + static_cast<size_t>(c)];
    T.extra.values(static_cast<Eigen::Index>(i), 0) = static_cast<double>(out_ref[order[i]]);
  }
  st.written = static_cast<long>(order.size());
  meta_set(T.meta, "positions", "refer to the keypoint of image1 (kp1 = its id in image1's matches files)");
  meta_set(T.meta, "min_views", std::to_string(o.min_views));
  if (stats) *stats = st;
  return T;
}

}  // namespace tpkit
