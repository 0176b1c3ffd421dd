#include "tpkit/match/tracks_chain.hpp"

#include <algorithm>
#include <functional>
#include <cmath>
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
  void check_closure(Index nb, Index ne, int ref, const std::vector<Index>& q, const std::vector<Eigen::Vector2d>& pos,
                     const std::vector<double>& pvar, const std::vector<char>& reached, std::vector<char>& have,
                     ChainStats* counts) const;
  mutable std::vector<Index> closure_order;  // scratch of check_closure
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
  std::vector<char> present(nimg), conflict(nimg), have(nimg);
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
    // breadth first from the reference keypoint(s)
    const size_t size = ne - nb;
    pos.resize(size);
    pvar.assign(size, std::numeric_limits<double>::quiet_NaN());
    reached.assign(size, 0);
    q.clear();
    for (Index c = nb; c < ne && image_of(comp_nodes[c]) == ref; ++c) {
      const Index n = comp_nodes[c];
      pos[c - nb] = {nodes[n].x, nodes[n].y};
      reached[c - nb] = 1;
      q.push_back(n);
    }
    std::fill(have.begin(), have.end(), 0);
    have[ref] = 1;
    view[ref] = {nodes[first[ref]].x, nodes[first[ref]].y};
    var[ref] = std::numeric_limits<double>::quiet_NaN();
    for (size_t head = 0; head < q.size(); ++head) {
      const Index n = q[head];
      const Eigen::Vector2d pn = pos[local[n]];
      const double vn = pvar[local[n]];
      for (Index a = adj_at[n]; a < adj_at[n + 1]; ++a) {
        const Index l = adj[a];
        const bool forward = lu[l] == n;
        const Index m = forward ? lv[l] : lu[l];
        const int im = image_of(m);
        const double half = 0.5 * static_cast<double>(lsig[l]) * static_cast<double>(lsig[l]);
        if (std::isnan(var[ref]) && image_of(n) == ref) var[ref] = half;  // the first record leaving the reference
        if (conflict[im] || reached[local[m]]) continue;
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
    if (o.closure > 0) check_closure(nb, ne, ref, q, pos, pvar, reached, have, conflicts);
    if (ref < K) f(ref, nodes[first[ref]].id, have, view, var);
  }
}

// Every link of the component whose two ends were reached: the position it gives its image-2 end from
// its image-1 end's position must be the breadth-first one (exactly so for the links of the search tree).
// Variance of the disagreement: the records of the cycle, 2 pvar(u) + 2 pvar(v) + sigma_l^2 (pvar holds
// half of each record's variance along the path).
void TrackChainer::Impl::check_closure(Index nb, Index ne, int ref, const std::vector<Index>& q,
                                       const std::vector<Eigen::Vector2d>& pos, const std::vector<double>& pvar,
                                       const std::vector<char>& reached, std::vector<char>& have,
                                       ChainStats* counts) const {
  std::vector<Index>& order = closure_order;
  order.assign(ne - nb, 0);
  for (size_t k = 0; k < q.size(); ++k) order[local[q[k]]] = static_cast<Index>(k);
  for (Index c = nb; c < ne; ++c) {
    const Index u = comp_nodes[c];
    if (!reached[local[u]]) continue;
    for (Index a = adj_at[u]; a < adj_at[u + 1]; ++a) {
      const Index l = adj[a];
      if (lu[l] != u) continue;  // each link once, from its image-1 end
      const Index v = lv[l];
      if (!reached[local[v]]) continue;
      const Eigen::Vector2d pv = Eigen::Vector2d(lx2[l], ly2[l]) + (pos[local[u]] - Eigen::Vector2d(nodes[u].x, nodes[u].y));
      const double d = (pv - pos[local[v]]).norm();
      const double zu = std::isnan(pvar[local[u]]) ? 0.0 : pvar[local[u]], zv = std::isnan(pvar[local[v]]) ? 0.0 : pvar[local[v]];
      const double sl = std::isnan(lsig[l]) ? 0.0 : static_cast<double>(lsig[l]);
      const double cycle_var = 2 * zu + 2 * zv + sl * sl;
      if (!(d > std::max(o.closure, 5 * std::sqrt(cycle_var)))) continue;
      const Index later = order[local[u]] > order[local[v]] ? u : v;
      const int im = image_of(later) == ref ? image_of(later == u ? v : u) : image_of(later);
      if (have[im]) {
        have[im] = 0;
        if (counts) ++counts->views_dropped_closure;
      }
    }
  }
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
    meta_set(T.meta, "closure", "redundant links agree within max(" + format_number(I.o.closure) + " px, 5 sigma of the cycle); " +
                                    std::to_string(I.st.views_dropped_closure) + " views dropped where they did not");
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
  if (stats) *stats = st;
  return T;
}

}  // namespace tpkit
