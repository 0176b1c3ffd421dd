// See cluster_search.hpp.
#include "tpkit/cluster/cluster_search.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <nanoflann.hpp>
#include <random>

namespace tpkit {

namespace {

template <int D>
struct VecCloud {
  const std::vector<std::array<double, D>>* v;
  size_t kdtree_get_point_count() const { return v->size(); }
  double kdtree_get_pt(size_t i, size_t d) const { return (*v)[i][d]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};
template <int D>
using VecTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, VecCloud<D>>, VecCloud<D>, D, int>;

struct Quad {
  int anchor;
  std::array<int, 4> idx;  // points ordered by the area of the triangle that leaves them out
  std::array<double, 3> desc;
};

inline double signed_area(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return 0.5 * ((b(0) - a(0)) * (c(1) - a(1)) - (b(1) - a(1)) * (c(0) - a(0)));
}

// Descriptor of four points; false when degenerate or when its ordering is ambiguous.
bool quad_descriptor(const Eigen::MatrixX2d& P, std::array<int, 4> q, Quad& out) {
  Eigen::Vector2d p[4];
  for (int k = 0; k < 4; ++k) p[k] = P.row(q[k]).transpose();
  double area[4];
  for (int m = 0; m < 4; ++m) {
    int o[3], n = 0;
    for (int k = 0; k < 4; ++k)
      if (k != m) o[n++] = k;
    area[m] = std::abs(signed_area(p[o[0]], p[o[1]], p[o[2]]));
  }
  std::array<int, 4> ord = {0, 1, 2, 3};
  std::sort(ord.begin(), ord.end(), [&](int a, int b) { return area[a] < area[b]; });
  double big = area[ord[3]];
  double span = 0;
  for (int k = 1; k < 4; ++k) span = std::max(span, (p[k] - p[0]).norm());
  if (!(big > 1e-6 * span * span) || big <= 0) return false;
  for (int k = 0; k < 3; ++k)
    if (area[ord[k + 1]] - area[ord[k]] < 0.03 * big) return false;
  if (area[ord[0]] < 0.02 * big) return false;  // three nearly collinear points
  Eigen::Vector2d r[4];
  for (int k = 0; k < 4; ++k) out.idx[k] = q[ord[k]], r[k] = p[ord[k]];
  double D[4];
  for (int m = 0; m < 4; ++m) {
    int o[3], n = 0;
    for (int k = 0; k < 4; ++k)
      if (k != m) o[n++] = k;
    D[m] = signed_area(r[o[0]], r[o[1]], r[o[2]]);
  }
  double s = std::abs(D[3]);
  out.desc = {D[0] / s, D[1] / s, D[2] / s};
  // The sign of D[3] is fixed by the others for an orientation-preserving map; make it +.
  if (D[3] < 0) out.desc = {-out.desc[0], -out.desc[1], -out.desc[2]};
  return true;
}

std::vector<Quad> make_quads(const Eigen::MatrixX2d& P, int k, int max_anchors, std::mt19937_64& rng) {
  std::vector<std::array<double, 2>> pts(static_cast<size_t>(P.rows()));
  for (Eigen::Index i = 0; i < P.rows(); ++i) pts[static_cast<size_t>(i)] = {P(i, 0), P(i, 1)};
  VecCloud<2> cloud{&pts};
  VecTree<2> tree(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  tree.buildIndex();
  std::vector<int> anchors(pts.size());
  for (size_t i = 0; i < anchors.size(); ++i) anchors[i] = static_cast<int>(i);
  if (static_cast<int>(anchors.size()) > max_anchors) {
    std::shuffle(anchors.begin(), anchors.end(), rng);
    anchors.resize(static_cast<size_t>(max_anchors));
  }
  int kk = std::min<int>(k + 1, static_cast<int>(pts.size()));
  std::vector<int> nn(static_cast<size_t>(kk));
  std::vector<double> d2(static_cast<size_t>(kk));
  std::vector<Quad> quads;
  for (int a : anchors) {
    size_t got = tree.knnSearch(pts[static_cast<size_t>(a)].data(), static_cast<size_t>(kk), nn.data(), d2.data());
    std::vector<int> nb;
    for (size_t t = 0; t < got; ++t)
      if (nn[t] != a) nb.push_back(nn[t]);
    int m = static_cast<int>(nb.size());
    for (int x = 0; x < m; ++x)
      for (int y = x + 1; y < m; ++y)
        for (int z = y + 1; z < m; ++z) {
          Quad q;
          q.anchor = a;
          if (quad_descriptor(P, {a, nb[x], nb[y], nb[z]}, q)) quads.push_back(q);
        }
  }
  return quads;
}

// Affine map (as a homography) from four correspondences, least squares; false if degenerate.
bool affine_from(const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B, const Quad& qa, const Quad& qb,
                 Eigen::Matrix3d& H, double& rms) {
  Eigen::Matrix<double, 4, 3> M;
  Eigen::Matrix<double, 4, 2> R;
  for (int k = 0; k < 4; ++k) {
    M.row(k) << A(qa.idx[k], 0), A(qa.idx[k], 1), 1.0;
    R.row(k) << B(qb.idx[k], 0), B(qb.idx[k], 1);
  }
  Eigen::Vector2d ca = M.leftCols<2>().colwise().mean().transpose(), cb = R.colwise().mean().transpose();
  for (int k = 0; k < 4; ++k) M(k, 0) -= ca(0), M(k, 1) -= ca(1), R(k, 0) -= cb(0), R(k, 1) -= cb(1);
  Eigen::ColPivHouseholderQR<Eigen::Matrix<double, 4, 3>> qr(M);
  if (qr.rank() < 3) return false;
  Eigen::Matrix<double, 3, 2> X = qr.solve(R);
  Eigen::Matrix2d L = X.topRows<2>().transpose();
  double det = L.determinant();
  if (!(det > 0) || !std::isfinite(det)) return false;
  double s1 = L.col(0).norm(), s2 = L.col(1).norm();
  if (s1 > 20 * s2 || s2 > 20 * s1) return false;
  rms = std::sqrt((M * X - R).squaredNorm() / 4.0);
  Eigen::Vector2d t = cb + X.row(2).transpose() - L * ca;
  H << L(0, 0), L(0, 1), t(0), L(1, 0), L(1, 1), t(1), 0, 0, 1;
  return true;
}

}  // namespace

std::vector<SearchHypothesis> search_hypotheses(const ClusterCost& cost, const SearchOptions& opt, long* tried) {
  std::mt19937_64 rng(opt.seed);
  const Eigen::MatrixX2d& A = cost.a();
  Eigen::MatrixX2d B = cost.b();
  std::vector<SearchHypothesis> out;
  if (tried) *tried = 0;
  if (A.rows() < 4 || B.rows() < 4) return out;
  // Dense clusters: near-neighbour quadruples are small against the noise, so their descriptors are
  // less distinctive among many more of B's; try more matches per quadruple from fewer anchors of B.
  SearchOptions o = opt;
  double dtol = 0.01;
  if (B.rows() > 2000) {
    o.max_anchors_b = std::min(o.max_anchors_b, 1500 * std::max(1, opt.widen));
    o.max_anchors_a = std::max(o.max_anchors_a, 300 * std::max(1, opt.widen));
    o.matches_per_quad = std::max(o.matches_per_quad, 24);
    dtol = 0.03;
  }
  // Sparse clusters use every anchor already: a wider search takes larger neighbourhoods instead, so
  // that more quadruples have all four partners (with half the points unmatched, few of 5 do).
  if (B.rows() <= 2000 && opt.widen > 1) o.k_a += 2, o.k_b += 4;
  std::vector<Quad> qa = make_quads(A, o.k_a, o.max_anchors_a, rng);
  // Scoring sets: the `local` nearest neighbours of each anchor of A; tolerance from B's point spacing.
  std::vector<std::array<double, 2>> pa(static_cast<size_t>(A.rows()));
  for (Eigen::Index i = 0; i < A.rows(); ++i) pa[static_cast<size_t>(i)] = {A(i, 0), A(i, 1)};
  VecCloud<2> ca{&pa};
  VecTree<2> ta(2, ca, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  ta.buildIndex();
  std::map<int, std::pair<std::vector<int>, double>> local;  // anchor -> (neighbours, radius)
  int nl = std::min<int>(opt.local, static_cast<int>(A.rows()));
  for (const Quad& q : qa) {
    if (local.count(q.anchor)) continue;
    std::vector<int> nn(static_cast<size_t>(nl));
    std::vector<double> d2(static_cast<size_t>(nl));
    size_t got = ta.knnSearch(pa[static_cast<size_t>(q.anchor)].data(), static_cast<size_t>(nl), nn.data(), d2.data());
    nn.resize(got);
    local[q.anchor] = {nn, std::sqrt(d2[got - 1])};
  }
  Eigen::Vector2d span = B.colwise().maxCoeff() - B.colwise().minCoeff();
  double tol = std::max(0.3 * std::sqrt(std::max(span(0) * span(1), 1.0) / static_cast<double>(B.rows())), 1e-3);
  std::vector<SearchHypothesis> all;
  long n_tried = 0;
  for (int mirror = 0; mirror < (opt.allow_reflection ? 2 : 1); ++mirror) {
    Eigen::MatrixX2d Bm = B;
    if (mirror) Bm.col(0) = -Bm.col(0);
    std::vector<Quad> qb = make_quads(Bm, o.k_b, o.max_anchors_b, rng);
    if (qb.empty() || qa.empty()) continue;
    std::vector<std::array<double, 3>> db(qb.size());
    for (size_t i = 0; i < qb.size(); ++i) db[i] = qb[i].desc;
    VecCloud<3> cloud{&db};
    VecTree<3> tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree.buildIndex();
    int km = std::min<int>(o.matches_per_quad, static_cast<int>(qb.size()));
    std::vector<int> nn(static_cast<size_t>(km));
    std::vector<double> d2(static_cast<size_t>(km));
    Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
    if (mirror) M(0, 0) = -1;
    for (const Quad& q : qa) {
      size_t got = tree.knnSearch(q.desc.data(), static_cast<size_t>(km), nn.data(), d2.data());
      for (size_t t = 0; t < got; ++t) {
        if (d2[t] > dtol) continue;
        Eigen::Matrix3d H;
        double rms;
        if (!affine_from(A, Bm, q, qb[static_cast<size_t>(nn[t])], H, rms)) continue;
        if (rms > tol) continue;
        H = M * H;  // back from the mirrored B
        ++n_tried;
        const auto& loc = local[q.anchor];
        std::vector<int> quick(loc.first.begin(), loc.first.begin() + std::min<size_t>(8, loc.first.size()));
        double s = cost.forward_truncated(H, quick, tol);
        if (s > 0.6 * tol) continue;
        // The score leaves out the quadruple's own points (any hypothesis fits them) and truncates at a
        // third of the gate: with many unmatched points, the few true matches among the neighbours lie
        // at the noise level while a wrong map's chance neighbours are spread over the gate.
        std::vector<int> others;
        for (int i : loc.first)
          if (std::find(q.idx.begin(), q.idx.end(), i) == q.idx.end()) others.push_back(i);
        s = cost.forward_truncated(H, others, tol / 3);
        all.push_back({H, s, A.row(q.anchor).transpose(), loc.second});
      }
    }
  }
  if (tried) *tried = n_tried;
  std::sort(all.begin(), all.end(), [](const SearchHypothesis& a, const SearchHypothesis& b) { return a.score < b.score; });
  // Keep distinct hypotheses: they differ by more than tol somewhere on A's bounding box.
  Eigen::Vector2d lo = A.colwise().minCoeff(), hi = A.colwise().maxCoeff();
  Eigen::MatrixX2d corners(4, 2);
  corners << lo(0), lo(1), hi(0), lo(1), lo(0), hi(1), hi(0), hi(1);
  for (const auto& h : all) {
    bool dup = false;
    for (const auto& k : out)
      if (homography_max_difference(h.H, k.H, corners) < tol) {
        dup = true;
        break;
      }
    if (!dup) out.push_back(h);
    if (static_cast<int>(out.size()) >= opt.keep) break;
  }
  return out;
}

}  // namespace tpkit
