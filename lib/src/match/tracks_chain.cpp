#include "tpkit/match/tracks_chain.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <functional>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <set>

#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {
using Index = std::uint32_t;  // nodes and links; more than 2^31 of either is refused
constexpr std::uint64_t kMaxIndex = (std::uint64_t{1} << 31) - 1;

// An array grown by chunks of 2^16 elements: no reallocation, so no copy of everything held and no
// moment with two copies in memory while matches files are added.
template <class T>
class Chunked {
 public:
  void push_back(const T& v) {
    if ((n_ & kMask) == 0) chunks_.emplace_back(new T[kChunk]);
    chunks_.back()[n_ & kMask] = v;
    ++n_;
  }
  T& operator[](size_t i) { return chunks_[i >> kShift][i & kMask]; }
  const T& operator[](size_t i) const { return chunks_[i >> kShift][i & kMask]; }
  size_t size() const { return n_; }
  void release() {
    chunks_.clear();
    chunks_.shrink_to_fit();
    n_ = 0;
  }

 private:
  static constexpr size_t kShift = 16, kChunk = size_t{1} << kShift, kMask = kChunk - 1;
  std::vector<std::unique_ptr<T[]>> chunks_;
  size_t n_ = 0;
};

struct UnionFind {
  std::vector<Index> p;
  Index find(Index a) {
    while (p[a] != a) a = p[a] = p[p[a]];
    return a;
  }
  // smallest index as root: the root of a component is its first node (reference image, smallest id)
  void unite(Index a, Index b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (b < a) std::swap(a, b);
    p[b] = a;
  }
};

std::string canonical(const std::string& p) {
  std::error_code ec;
  auto c = std::filesystem::weakly_canonical(p, ec);
  return ec ? p : c.string();
}

struct Keypoint {
  long long id;
  double x, y;  // keypoint position
};

// An estimate written with the digits it has (sigmas are held as float).
double four_digits(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return std::strtod(buf, nullptr);
}

struct FileSpan {
  int a, b;            // images of the file (image 1, image 2)
  size_t begin, end;   // its links
};
}  // namespace

struct TrackChainer::Impl {
  ChainOptions o;
  ChainStats st;
  std::vector<ImageRef> imgs;
  std::vector<std::string> canon;
  std::vector<char> seen_given;
  bool has_sigma = true;
  bool joined = false;
  int K = 0;
  // while adding: per image its keypoint occurrences (one per record end); links refer to them
  std::vector<Chunked<Keypoint>> occ;
  std::vector<FileSpan> files;
  // links (a record each): u in the file's image 1, v in its image 2 (occurrence indices while adding,
  // node indices after join), the refined position of v relative to u's keypoint, the record's sigma
  Chunked<Index> lu, lv;
  Chunked<double> lx2, ly2;
  Chunked<float> lsig;
  // after join: nodes ordered by image, then keypoint id; image i's nodes are [base[i], base[i+1])
  Chunked<Keypoint> nodes;
  std::vector<size_t> base;
  std::vector<Index> adj_at, adj, comp_at, comp_nodes, local;

  int image_index(const ImageRef& r, bool add) {
    for (size_t i = 0; i < imgs.size(); ++i)
      if (imgs[i].path == r.path) return static_cast<int>(i);
    std::string c = canonical(r.path);
    for (size_t i = 0; i < imgs.size(); ++i)
      if (canon[i] == c) return static_cast<int>(i);
    if (!add) return -1;
    imgs.push_back(r);
    canon.push_back(c);
    occ.emplace_back();
    return static_cast<int>(imgs.size() - 1);
  }
  int image_of(Index n) const {
    return static_cast<int>(std::upper_bound(base.begin(), base.end(), static_cast<size_t>(n)) - base.begin()) - 1;
  }

  void add(const Matches& m);
  void join();
  void dedup_keypoints();
  void merge_same_positions(UnionFind& uf);
  void build_adjacency();
  void build_components(UnionFind& uf);
  // Walks every component in output order; calls f(ref image, reference keypoint id, have, view, var)
  // for each track holding the reference without conflict.
  // `conflicts`, when not null, counts the conflicts (the first walk).
  template <class F>
  void walk(F&& f, ChainStats* conflicts) const;
  // Loop closure over every cycle of a track's links (see the header): the views and links to leave out.
  // `q`: the nodes reached by the first breadth-first walk, in its order; `usable[im]`: image im holds
  // one point of the track (no conflict). Returns whether anything is left out.
  bool close_loops(const std::vector<Index>& q, const std::vector<char>& usable, std::vector<char>& drop_view,
                   std::vector<Index>& drop_links, long& views_dropped, long& links_dropped) const;
};

void TrackChainer::Impl::add(const Matches& m) {
  if (joined) throw std::logic_error("TrackChainer::add after join");
  if (m.image1.path.empty() || m.image2.path.empty())
    throw InputError(m.source, 0, "matches file without image1/image2 header lines: tp-chain needs them to join files");
  int ab[2];
  int k = 0;
  for (const ImageRef* r : {&m.image1, &m.image2}) {
    const int i = image_index(*r, true);
    ab[k++] = i;
    if (i < static_cast<int>(seen_given.size())) {
      seen_given[i] = 1;
      if (imgs[i].width == 0) {
        imgs[i].width = r->width;
        imgs[i].height = r->height;
      }
    }
  }
  if (ab[0] == ab[1]) throw InputError(m.source, 0, "both images of the file are the same image");
  if (lu.size() + m.size() > kMaxIndex || occ[ab[0]].size() + m.size() > kMaxIndex || occ[ab[1]].size() + m.size() > kMaxIndex)
    throw InputError(m.source, 0, "more than 2^31 matches in one chain: chain the study area's groups of images apart");
  const int ckx = m.extra.find("kx2"), cky = m.extra.find("ky2"), cs = m.extra.find("sigma"), crf = m.extra.find("refined");
  if (cs < 0) has_sigma = false;
  const size_t begin = lu.size();
  for (size_t r = 0; r < m.size(); ++r) {
    const Eigen::Index e = static_cast<Eigen::Index>(r);
    if (crf >= 0 && !o.unrefined && m.extra.values(e, crf) == 0) {
      ++st.unrefined_left_out;
      continue;
    }
    const double kx = ckx >= 0 ? m.extra.values(e, ckx) : m.xy(e, 2);
    const double ky = cky >= 0 ? m.extra.values(e, cky) : m.xy(e, 3);
    lu.push_back(static_cast<Index>(occ[ab[0]].size()));
    occ[ab[0]].push_back({m.id1[r], m.xy(e, 0), m.xy(e, 1)});
    lv.push_back(static_cast<Index>(occ[ab[1]].size()));
    occ[ab[1]].push_back({m.id2[r], kx, ky});
    lx2.push_back(m.xy(e, 2));
    ly2.push_back(m.xy(e, 3));
    const double sigma = cs >= 0 ? m.extra.values(e, cs) : std::numeric_limits<double>::quiet_NaN();
    // squared into a variance, -1 would pass as 1 (rpc-adjust and tp-ground refuse it alike)
    if (sigma < 0)
      throw InputError(m.source, r < m.line.size() ? m.line[r] : 0,
                       "sigma " + format_number(sigma) + " is not a standard deviation (pixels, >= 0)");
    lsig.push_back(static_cast<float>(sigma));
  }
  files.push_back({ab[0], ab[1], begin, lu.size()});
}

// Occurrences of one (image, id) become one node (the first occurrence's position), image by image, so
// that at any time only one image's occurrences and permutation are held beside the nodes made so far.
void TrackChainer::Impl::dedup_keypoints() {
  base.assign(imgs.size() + 1, 0);
  std::vector<Index> perm, node_of;
  for (size_t i = 0; i < imgs.size(); ++i) {
    base[i] = nodes.size();
    Chunked<Keypoint>& oc = occ[i];
    perm.resize(oc.size());
    for (size_t j = 0; j < perm.size(); ++j) perm[j] = static_cast<Index>(j);
    std::sort(perm.begin(), perm.end(), [&](Index p, Index q) { return oc[p].id < oc[q].id || (oc[p].id == oc[q].id && p < q); });
    node_of.assign(oc.size(), 0);
    for (size_t j = 0; j < perm.size(); ++j) {
      if (j == 0 || oc[perm[j]].id != oc[perm[j - 1]].id) nodes.push_back(oc[perm[j]]);
      node_of[perm[j]] = static_cast<Index>(nodes.size() - 1);
    }
    for (const FileSpan& f : files) {
      if (f.a == static_cast<int>(i))
        for (size_t l = f.begin; l < f.end; ++l) lu[l] = node_of[lu[l]];
      if (f.b == static_cast<int>(i))
        for (size_t l = f.begin; l < f.end; ++l) lv[l] = node_of[lv[l]];
    }
    oc.release();
  }
  base[imgs.size()] = nodes.size();
  std::vector<Chunked<Keypoint>>().swap(occ);
  std::vector<Index>().swap(perm);
  std::vector<Index>().swap(node_of);
}

// Same-position keypoints of one image are one point: every pair (p, q) of one image with
// |x_q - x_p| <= same_position and |y_q - y_p| <= same_position is joined. A sweep in x order with the
// window of the points within same_position in x, searched by y: O(n log n + pairs found) per image
// (the plain window scan was O(n * points in a same_position-wide strip), quadratic on a grid).
void TrackChainer::Impl::merge_same_positions(UnionFind& uf) {
  const double sp = o.same_position;
  auto join_nodes = [&](Index p, Index q) {
    if (uf.find(p) != uf.find(q)) {
      uf.unite(p, q);
      ++st.merged_duplicates;
    }
  };
  std::vector<Index> ns, rep;
  for (size_t img = 0; img < imgs.size(); ++img) {
    ns.resize(base[img + 1] - base[img]);
    for (size_t j = 0; j < ns.size(); ++j) ns[j] = static_cast<Index>(base[img] + j);
    std::sort(ns.begin(), ns.end(), [&](Index p, Index q) {
      if (nodes[p].x != nodes[q].x) return nodes[p].x < nodes[q].x;
      if (nodes[p].y != nodes[q].y) return nodes[p].y < nodes[q].y;
      return p < q;
    });
    // Keypoints at exactly the same position: joined to the first of them, which stands for them all
    // below (the test depends on the coordinates only).
    rep.clear();
    for (size_t i = 0; i < ns.size(); ++i) {
      if (!rep.empty() && nodes[ns[i]].x == nodes[rep.back()].x && nodes[ns[i]].y == nodes[rep.back()].y)
        join_nodes(rep.back(), ns[i]);
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
      const Keypoint& nj = nodes[rep[j]];
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
          if (std::abs(nj.y - nodes[rep[i]].y) <= sp) join_nodes(rep[i], rep[j]);
      } else {
        auto it = act.lower_bound({nj.y, 0});
        for (auto u = it; u != act.end() && u->first - nj.y <= sp; ++u) join_nodes(rep[u->second], rep[j]);
        for (auto d = it; d != act.begin();) {
          --d;
          if (nj.y - d->first > sp) break;
          join_nodes(rep[d->second], rep[j]);
        }
        act.emplace(nj.y, j);
      }
    }
  }
}

// links of each node, in link order (compressed rows)
void TrackChainer::Impl::build_adjacency() {
  const size_t N = nodes.size(), L = lu.size();
  adj_at.assign(N + 1, 0);
  for (size_t l = 0; l < L; ++l) ++adj_at[lu[l] + 1], ++adj_at[lv[l] + 1];
  for (size_t n = 0; n < N; ++n) adj_at[n + 1] += adj_at[n];
  adj.resize(adj_at[N]);
  std::vector<Index> fill(adj_at.begin(), adj_at.end() - 1);
  for (size_t l = 0; l < L; ++l) {
    adj[fill[lu[l]]++] = static_cast<Index>(l);
    adj[fill[lv[l]]++] = static_cast<Index>(l);
  }
}

// components: nodes grouped by root (compressed rows), each group in node order (image, then id); the
// union-find's array is then reused as each node's index within its component
void TrackChainer::Impl::build_components(UnionFind& uf) {
  const size_t N = nodes.size();
  for (size_t n = 0; n < N; ++n) uf.p[n] = uf.find(static_cast<Index>(n));
  comp_at.assign(N + 1, 0);
  for (size_t n = 0; n < N; ++n) ++comp_at[uf.p[n] + 1];
  for (size_t n = 0; n < N; ++n) {
    if (comp_at[n + 1] > 0) ++st.components;
    comp_at[n + 1] += comp_at[n];
  }
  comp_nodes.resize(N);
  std::vector<Index> fill(comp_at.begin(), comp_at.end() - 1);
  for (size_t n = 0; n < N; ++n) {
    const Index at = fill[uf.p[n]]++;
    comp_nodes[at] = static_cast<Index>(n);
    uf.p[n] = at - comp_at[uf.p[n]];
  }
  local.swap(uf.p);
}

void TrackChainer::Impl::join() {
  const size_t given = o.images.size();
  for (size_t k = 0; k < given; ++k)
    if (!seen_given[k]) throw InputError(o.images[k], 0, "image given with --images appears in no matches file");
  K = given ? static_cast<int>(given) : static_cast<int>(imgs.size());
  if (o.min_views < 2) throw UsageError("--min-views must be at least 2");
  if (o.min_views > K)
    throw UsageError("--min-views " + std::to_string(o.min_views) + " is more than the " + std::to_string(K) + " images");
  if (files.empty()) has_sigma = false;
  dedup_keypoints();
  UnionFind uf;
  uf.p.resize(nodes.size());
  for (size_t n = 0; n < nodes.size(); ++n) uf.p[n] = static_cast<Index>(n);
  for (size_t l = 0; l < lu.size(); ++l) uf.unite(lu[l], lv[l]);
  merge_same_positions(uf);
  build_adjacency();
  build_components(uf);
  joined = true;
  // first walk: the counts (the header names them before the tracks)
  walk([&](int, long long, const std::vector<char>& have, const std::vector<Eigen::Vector2d>&, const std::vector<double>&) {
    int views = 0;
    for (int im = 0; im < K; ++im) views += have[im];
    if (views >= 2) st.by_length[views]++;
    if (views >= o.min_views) {
      st.written_by_length[views]++;
      ++st.written;
    }
  }, &st);
}

template <class F>
void TrackChainer::Impl::walk(F&& f, ChainStats* conflicts) const {
  auto same = [&](Index p, Index q) {
    return std::abs(nodes[p].x - nodes[q].x) <= o.same_position && std::abs(nodes[p].y - nodes[q].y) <= o.same_position;
  };
  const size_t nimg = imgs.size();
  std::vector<char> present(nimg), conflict(nimg), have(nimg), usable(nimg), drop_view(nimg);
  std::vector<Index> drop_links;
  std::vector<Index> first(nimg);
  std::vector<Eigen::Vector2d> view(nimg);
  std::vector<double> var(nimg);
  // per component (indexed by local): position, variance, reached
  std::vector<Eigen::Vector2d> pos;
  std::vector<double> pvar;
  std::vector<char> reached;
  std::vector<Index> q;
  const size_t N = nodes.size();
  for (size_t rt = 0; rt < N; ++rt) {
    const Index nb = comp_at[rt], ne = comp_at[rt + 1];
    if (nb == ne) continue;
    // per image: conflicting (two different positions)?
    std::fill(present.begin(), present.end(), 0);
    std::fill(conflict.begin(), conflict.end(), 0);
    for (Index c = nb; c < ne; ++c) {
      const Index n = comp_nodes[c];
      const int im = image_of(n);
      if (!present[im]) {
        present[im] = 1;
        first[im] = n;
      } else if (!same(first[im], n)) {
        conflict[im] = 1;
      }
    }
    const int ref = image_of(comp_nodes[nb]);  // nodes in image order: the first image present
    if (conflict[ref]) {
      if (conflicts) ++conflicts->dropped_reference_conflicts;
      continue;
    }
    if (conflicts)
      for (size_t im = 0; im < nimg; ++im)
        if (conflict[im]) ++conflicts->views_dropped_conflicts;
    // breadth first from the reference keypoint(s), through no dropped view or link
    const size_t size = ne - nb;
    auto breadth_first = [&](int r) {
      pos.resize(size);
      pvar.assign(size, std::numeric_limits<double>::quiet_NaN());
      reached.assign(size, 0);
      q.clear();
      for (Index c = nb; c < ne; ++c) {
        const Index n = comp_nodes[c];
        if (image_of(n) != r) continue;
        pos[c - nb] = {nodes[n].x, nodes[n].y};
        reached[c - nb] = 1;
        q.push_back(n);
      }
      std::fill(have.begin(), have.end(), 0);
      have[r] = 1;
      view[r] = {nodes[first[r]].x, nodes[first[r]].y};
      var[r] = std::numeric_limits<double>::quiet_NaN();
      for (size_t head = 0; head < q.size(); ++head) {
        const Index n = q[head];
        const Eigen::Vector2d pn = pos[local[n]];
        const double vn = pvar[local[n]];
        for (Index a = adj_at[n]; a < adj_at[n + 1]; ++a) {
          const Index l = adj[a];
          const bool forward = lu[l] == n;
          const Index m = forward ? lv[l] : lu[l];
          const int im = image_of(m);
          if (!drop_links.empty() && std::binary_search(drop_links.begin(), drop_links.end(), l)) continue;
          const double half = 0.5 * static_cast<double>(lsig[l]) * static_cast<double>(lsig[l]);
          if (std::isnan(var[r]) && image_of(n) == r && !drop_view[im]) var[r] = half;  // the first record leaving the reference
          if (conflict[im] || drop_view[im] || reached[local[m]]) continue;
          Eigen::Vector2d pm;
          if (forward)  // refined position in image 2, moved by n's offset from its keypoint
            pm = Eigen::Vector2d(lx2[l], ly2[l]) + (pn - Eigen::Vector2d(nodes[n].x, nodes[n].y));
          else  // reversed: x2 is n's refined position relative to m's keypoint
            pm = Eigen::Vector2d(nodes[m].x, nodes[m].y) - (Eigen::Vector2d(lx2[l], ly2[l]) - pn);
          pos[local[m]] = pm;
          pvar[local[m]] = (std::isnan(vn) ? 0.0 : vn) + half;
          reached[local[m]] = 1;
          q.push_back(m);
          if (!have[im]) {
            have[im] = 1;
            view[im] = pm;
            var[im] = pvar[local[m]];
          }
        }
      }
    };
    std::fill(drop_view.begin(), drop_view.end(), 0);
    drop_links.clear();
    int r = ref;
    breadth_first(r);
    if (o.closure > 0) {
      for (size_t im = 0; im < nimg; ++im) usable[im] = have[im];
      long vd = 0, ld = 0;
      if (close_loops(q, usable, drop_view, drop_links, vd, ld)) {
        // the reference itself may have gone: the track then refers to its next image's keypoint
        if (drop_view[r]) {
          r = 0;
          while (r < static_cast<int>(nimg) && !(usable[r] && !drop_view[r])) ++r;
        }
        breadth_first(r);
        for (size_t im = 0; im < nimg; ++im)
          if (usable[im] && !have[im] && !drop_view[im]) ++vd;  // cut off from the reference by the drops
        if (conflicts) conflicts->views_dropped_closure += vd, conflicts->links_dropped_closure += ld;
      }
    }
    if (r < K) f(r, nodes[first[r]].id, have, view, var);
  }
}

// Loop closure. Unknowns: each view's offset o(im) = position - keypoint position (pixels, x and y
// apart; the reference's is 0). A link (record) between keypoint u of image a (its image 1) and
// keypoint v of image b says o(b) - o(a) = d = (x2, y2) - kp(v), weight 1 / (sigma^2 + 0.02^2). The
// links of a track over-determine the offsets wherever they close a cycle; each link is compared with
// what all the others say (least squares without it: the residual r / (1 - h), h its leverage, of
// variance sigma^2 + that of the prediction), which covers every cycle of the track at once, not only
// the triplets. Tolerance: max(closure, 5 sigma of that difference). While a link fails, the worst
// (largest failure over its tolerance) is left out and the fit redone (data snooping); where the worst
// ties with others (one cycle, whose links all say the same: the error cannot be placed), the view most
// of them share goes, the one reached later on a tie. Then a view most of whose links went, the view
// inconsistent with the most others, loses its place (a wrong view's records go one by one until its
// last, which nothing contradicts any more); two good views joined by one bad record keep theirs.
bool TrackChainer::Impl::close_loops(const std::vector<Index>& q, const std::vector<char>& usable,
                                     std::vector<char>& drop_view, std::vector<Index>& drop_links, long& views_dropped,
                                     long& links_dropped) const {
  // the views (images) of the track in the order the walk reached them; the reference first
  std::vector<int> slot(imgs.size(), -1), image_at;
  for (Index n : q) {
    const int im = image_of(n);
    if (usable[im] && slot[im] < 0) {
      slot[im] = static_cast<int>(image_at.size());
      image_at.push_back(im);
    }
  }
  const int V = static_cast<int>(image_at.size());
  if (V < 3) return false;  // two views close no cycle
  struct Link {
    Index id;
    int a, b;  // view slots, o(b) - o(a) = d
    Eigen::Vector2d d;
    double s2, w;
  };
  std::vector<Link> links;
  for (Index u : q) {
    if (slot[image_of(u)] < 0) continue;
    for (Index k = adj_at[u]; k < adj_at[u + 1]; ++k) {
      const Index l = adj[k];
      if (lu[l] != u) continue;  // each link once, from its image-1 end
      const Index v = lv[l];
      const int sb = slot[image_of(v)];
      if (sb < 0) continue;
      const double sg = std::isnan(lsig[l]) ? 0.0 : static_cast<double>(lsig[l]);
      links.push_back({l, slot[image_of(u)], sb, Eigen::Vector2d(lx2[l] - nodes[v].x, ly2[l] - nodes[v].y), sg * sg,
                       1.0 / (sg * sg + 0.02 * 0.02)});
    }
  }
  if (static_cast<int>(links.size()) < V) return false;  // a tree: nothing to compare
  std::vector<char> view_out(static_cast<size_t>(V), 0), link_out(links.size(), 0);
  bool changed = false;
  int root = 0;  // the slot whose offset is held at 0
  std::vector<int> unk(static_cast<size_t>(V));
  std::vector<int> fails(static_cast<size_t>(V)), count(static_cast<size_t>(V));
  std::vector<double> excess(links.size());
  for (;;) {
    // the views still linked to the root (a drop may cut some off: they go with it)
    std::vector<char> seen(static_cast<size_t>(V), 0);
    seen[static_cast<size_t>(root)] = 1;
    for (bool grew = true; grew;) {
      grew = false;
      for (size_t k = 0; k < links.size(); ++k)
        if (!link_out[k] && seen[static_cast<size_t>(links[k].a)] != seen[static_cast<size_t>(links[k].b)]) {
          seen[static_cast<size_t>(links[k].a)] = seen[static_cast<size_t>(links[k].b)] = 1;
          grew = true;
        }
    }
    int m = 0;
    for (int v = 0; v < V; ++v) unk[static_cast<size_t>(v)] = (seen[static_cast<size_t>(v)] && v != root) ? m++ : -1;
    long alive = 0;
    for (size_t k = 0; k < links.size(); ++k) alive += !link_out[k] && seen[static_cast<size_t>(links[k].a)];
    if (alive <= m) break;  // no cycle left
    Eigen::MatrixXd N = Eigen::MatrixXd::Zero(m, m);
    Eigen::MatrixX2d rhs = Eigen::MatrixX2d::Zero(m, 2);
    for (size_t k = 0; k < links.size(); ++k) {
      const Link& L = links[k];
      if (link_out[k] || !seen[static_cast<size_t>(L.a)]) continue;
      const int ia = unk[static_cast<size_t>(L.a)], ib = unk[static_cast<size_t>(L.b)];
      if (ia >= 0) N(ia, ia) += L.w, rhs.row(ia) -= L.w * L.d.transpose();
      if (ib >= 0) N(ib, ib) += L.w, rhs.row(ib) += L.w * L.d.transpose();
      if (ia >= 0 && ib >= 0) N(ia, ib) -= L.w, N(ib, ia) -= L.w;
    }
    const Eigen::MatrixXd C = N.ldlt().solve(Eigen::MatrixXd::Identity(m, m));  // covariance of the offsets
    const Eigen::MatrixX2d off = C * rhs;
    auto offset = [&](int v) -> Eigen::Vector2d {
      const int i = unk[static_cast<size_t>(v)];
      return i < 0 ? Eigen::Vector2d(0, 0) : Eigen::Vector2d(off.row(i).transpose());
    };
    auto cov = [&](int i, int j) { return i < 0 || j < 0 ? 0.0 : C(i, j); };
    bool any = false;
    for (size_t k = 0; k < links.size(); ++k) {
      excess[k] = 0;
      const Link& L = links[k];
      if (link_out[k] || !seen[static_cast<size_t>(L.a)]) continue;
      const int ia = unk[static_cast<size_t>(L.a)], ib = unk[static_cast<size_t>(L.b)];
      const double qv = cov(ib, ib) + cov(ia, ia) - 2 * cov(ia, ib);  // variance of o(b) - o(a) from all links
      const double h = L.w * qv;                                       // the link's leverage
      if (h > 1 - 1e-9) continue;                                     // on no cycle: nothing to compare with
      const double e = (L.d - (offset(L.b) - offset(L.a))).norm() / (1 - h);
      const double tol = std::max(o.closure, 5 * std::sqrt(L.s2 + qv / (1 - h)));
      if (!(e > tol)) continue;
      excess[k] = e / tol;
      any = true;
    }
    if (!any) break;
    changed = true;
    // the worst link goes; where it ties with others (a single cycle: every link of it says the same,
    // the error cannot be placed), the view most of the tied links share goes, the one reached later
    // on a tie (a triplet's third view)
    size_t worst = 0;
    for (size_t k = 1; k < links.size(); ++k)
      if (excess[k] > excess[worst]) worst = k;
    std::fill(fails.begin(), fails.end(), 0);
    int tied = 0;
    for (size_t k = 0; k < links.size(); ++k)
      if (excess[k] > 0 && excess[k] >= excess[worst] * (1 - 1e-6)) {
        ++tied;
        ++fails[static_cast<size_t>(links[k].a)], ++fails[static_cast<size_t>(links[k].b)];
      }
    if (tied == 1) {
      link_out[worst] = 1;
      continue;
    }
    int w = 0;
    for (int v = 1; v < V; ++v)
      if (fails[static_cast<size_t>(v)] >= fails[static_cast<size_t>(w)]) w = v;
    view_out[static_cast<size_t>(w)] = 1;
    for (size_t k = 0; k < links.size(); ++k)
      if (links[k].a == w || links[k].b == w) link_out[k] = 1;
    if (w == root) {  // the next view reached holds the offsets
      root = 0;
      while (view_out[static_cast<size_t>(root)]) ++root;
    }
  }
  if (!changed) return false;
  // a view most of whose links (to the views kept) went is not placed by the track: it goes too, the
  // worst first (a wrong view keeps one link, the last of a cycle, which nothing contradicts)
  for (;;) {
    std::fill(fails.begin(), fails.end(), 0);
    std::fill(count.begin(), count.end(), 0);
    for (size_t k = 0; k < links.size(); ++k) {
      const Link& L = links[k];
      if (view_out[static_cast<size_t>(L.a)] || view_out[static_cast<size_t>(L.b)]) continue;
      ++count[static_cast<size_t>(L.a)], ++count[static_cast<size_t>(L.b)];
      if (link_out[k]) ++fails[static_cast<size_t>(L.a)], ++fails[static_cast<size_t>(L.b)];
    }
    int w = -1;
    for (int v = 0; v < V; ++v) {
      const size_t z = static_cast<size_t>(v);
      if (view_out[z] || !(2 * fails[z] > count[z])) continue;
      if (w < 0 || fails[z] * count[static_cast<size_t>(w)] >= fails[static_cast<size_t>(w)] * count[z]) w = v;
    }
    if (w < 0) break;
    view_out[static_cast<size_t>(w)] = 1;
  }
  for (int v = 0; v < V; ++v)
    if (view_out[static_cast<size_t>(v)]) {
      drop_view[static_cast<size_t>(image_at[static_cast<size_t>(v)])] = 1;
      ++views_dropped;
    }
  for (size_t k = 0; k < links.size(); ++k)
    if (link_out[k] && !view_out[static_cast<size_t>(links[k].a)] && !view_out[static_cast<size_t>(links[k].b)]) {
      drop_links.push_back(links[k].id);
      ++links_dropped;
    }
  std::sort(drop_links.begin(), drop_links.end());
  return true;
}

TrackChainer::TrackChainer(const ChainOptions& o) : impl_(std::make_unique<Impl>()) {
  impl_->o = o;
  for (const auto& p : o.images) impl_->image_index(ImageRef{p, 0, 0}, true);
  impl_->seen_given.assign(o.images.size(), 0);
}

TrackChainer::~TrackChainer() = default;

void TrackChainer::add(const Matches& m) { impl_->add(m); }

void TrackChainer::set_min_views(int n) { impl_->o.min_views = n; }

const ChainStats& TrackChainer::join() {
  impl_->join();
  return impl_->st;
}

Tracks TrackChainer::header() const {
  const Impl& I = *impl_;
  Tracks T;
  T.images.assign(I.imgs.begin(), I.imgs.begin() + I.K);
  T.xy.resize(0, 2 * I.K);
  T.extra.names = {"kp", "ref"};
  if (I.has_sigma)
    for (int v = 1; v <= I.K; ++v) T.extra.names.push_back("sigma" + std::to_string(v));
  T.extra.values.resize(0, static_cast<Eigen::Index>(T.extra.names.size()));
  meta_set(T.meta, "positions", "refer to the reference keypoint: image number ref, its id kp in that image's matches files");
  meta_set(T.meta, "min_views", std::to_string(I.o.min_views));
  if (I.o.closure > 0)
    meta_set(T.meta, "closure", "every link agrees with what the track's other links say within max(" + format_number(I.o.closure) +
                                    " px, 5 sigma of the difference); " + std::to_string(I.st.views_dropped_closure) +
                                    " views dropped where most of their links did not, " + std::to_string(I.st.links_dropped_closure) +
                                    " single links left out");
  else
    meta_set(T.meta, "closure", "not checked");
  std::string counts;
  for (const auto& kv : I.st.written_by_length) counts += (counts.empty() ? "" : " ") + std::to_string(kv.first) + ":" + std::to_string(kv.second);
  meta_set(T.meta, "tracks_by_views", counts.empty() ? "none" : counts);
  if (I.has_sigma) meta_set(T.meta, "sigma", "px, each record's variance split between its two ends and added along the path");
  if (I.o.unrefined) meta_set(T.meta, "unrefined", "matches marked refined 0 chained at their keypoint positions");
  else if (I.st.unrefined_left_out > 0)
    meta_set(T.meta, "unrefined", std::to_string(I.st.unrefined_left_out) + " matches marked refined 0 left out (tp-chain --unrefined chains them)");
  return T;
}

void TrackChainer::for_each(const std::function<void(long long, const double*, const double*)>& f) const {
  const Impl& I = *impl_;
  if (!I.joined) throw std::logic_error("TrackChainer::for_each before join");
  const int K = I.K;
  std::vector<double> xy(static_cast<size_t>(2 * K)), extra(2 + (I.has_sigma ? static_cast<size_t>(K) : 0));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  long long track = 0;
  I.walk([&](int ref, long long kp, const std::vector<char>& have, const std::vector<Eigen::Vector2d>& view,
             const std::vector<double>& var) {
    int views = 0;
    for (int im = 0; im < K; ++im) views += have[im];
    if (views < I.o.min_views) return;
    extra[0] = static_cast<double>(kp);
    extra[1] = ref + 1;
    for (int im = 0; im < K; ++im) {
      xy[2 * im] = have[im] ? view[im].x() : nan;
      xy[2 * im + 1] = have[im] ? view[im].y() : nan;
      if (I.has_sigma) extra[2 + im] = have[im] ? four_digits(std::sqrt(var[im])) : nan;
    }
    f(track++, xy.data(), extra.data());
  }, nullptr);
}

void TrackChainer::write(std::ostream& os) const {
  const Tracks h = header();
  std::vector<std::string> cols = {"track"};
  for (int v = 1; v <= impl_->K; ++v) {
    cols.push_back("x" + std::to_string(v));
    cols.push_back("y" + std::to_string(v));
  }
  for (const auto& n : h.extra.names) cols.push_back(n);
  long complete = 0;
  auto it = impl_->st.written_by_length.find(impl_->K);
  if (it != impl_->st.written_by_length.end()) complete = it->second;
  write_header(os, "tracks", complete == impl_->st.written ? 1 : 2, h.images, h.meta, cols);
  const size_t nx = static_cast<size_t>(2 * impl_->K), ne = h.extra.names.size();
  std::vector<double> rec(1 + nx + ne);
  for_each([&](long long track, const double* xy, const double* extra) {
    rec[0] = static_cast<double>(track);
    std::copy(xy, xy + nx, rec.begin() + 1);
    std::copy(extra, extra + ne, rec.begin() + 1 + static_cast<std::ptrdiff_t>(nx));
    write_record(os, rec);
  });
}

Tracks chain_tracks(const std::vector<Matches>& files, const ChainOptions& o, ChainStats* stats) {
  TrackChainer c(o);
  for (const auto& m : files) c.add(m);
  const ChainStats st = c.join();
  Tracks T = chained_tracks(c, st);
  if (stats) *stats = st;
  return T;
}

Tracks chained_tracks(const TrackChainer& c, const ChainStats& st) {
  Tracks T = c.header();
  const Eigen::Index n = st.written, nx = T.xy.cols(), ne = static_cast<Eigen::Index>(T.extra.names.size());
  T.xy.resize(n, nx);
  T.extra.values.resize(n, ne);
  T.id.reserve(static_cast<size_t>(n));
  c.for_each([&](long long track, const double* xy, const double* extra) {
    const Eigen::Index r = static_cast<Eigen::Index>(track);
    T.id.push_back(track);
    for (Eigen::Index k = 0; k < nx; ++k) T.xy(r, k) = xy[k];
    for (Eigen::Index k = 0; k < ne; ++k) T.extra.values(r, k) = extra[k];
  });
  return T;
}

}  // namespace tpkit
