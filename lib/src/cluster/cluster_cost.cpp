// See cluster_cost.hpp.
#include "tpkit/cluster/cluster_cost.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <stdexcept>

#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {
struct Cloud {
  const Eigen::MatrixX2d* m;
  size_t kdtree_get_point_count() const { return static_cast<size_t>(m->rows()); }
  double kdtree_get_pt(size_t i, size_t d) const { return (*m)(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(d)); }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 2, int>;

double diag(const Eigen::MatrixX2d& m) {
  if (m.rows() == 0) return 1;
  return std::max(1.0, (m.colwise().maxCoeff() - m.colwise().minCoeff()).norm());
}

// Mean of the (robust) distances of one direction.
double robust_mean(std::vector<double>& d, const CostOptions& o) {
  if (d.empty()) return 0;
  if (o.trim_from_data) return data_trim(d).psi;
  if (o.truncate > 0)
    for (double& x : d) x = std::min(x, o.truncate);
  size_t keep = d.size();
  if (o.trim > 0) {
    keep = std::max<size_t>(1, static_cast<size_t>(std::ceil((1.0 - o.trim) * static_cast<double>(d.size()))));
    keep = std::min(keep, d.size());
    std::nth_element(d.begin(), d.begin() + (keep - 1), d.end());
  }
  double s = 0;
  for (size_t i = 0; i < keep; ++i) s += d[i];
  return s / static_cast<double>(keep);
}
}  // namespace

DataTrim data_trim(std::vector<double>& d) {
  const size_t n = d.size();
  if (n == 0) throw std::invalid_argument("data_trim: no distances");
  std::sort(d.begin(), d.end());
  const size_t k0 = std::min(n, std::max<size_t>(4, n / 10));
  double s = 0;
  for (size_t i = 0; i + 1 < k0; ++i) s += d[i];
  DataTrim best{n, std::numeric_limits<double>::infinity()};
  const double N = static_cast<double>(n);
  for (size_t k = k0; k <= n; ++k) {
    s += d[k - 1];
    const double xi = static_cast<double>(k) / N;
    const double psi = s / static_cast<double>(k) / (xi * std::sqrt(xi));
    if (psi < best.psi) best = {k, psi};
  }
  return best;
}

struct ClusterCost::Trees {
  Cloud ca, cb;
  Tree ta, tb;
  Trees(const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B)
      : ca{&A}, cb{&B}, ta(2, ca, nanoflann::KDTreeSingleIndexAdaptorParams(10)),
        tb(2, cb, nanoflann::KDTreeSingleIndexAdaptorParams(10)) {
    ta.buildIndex();
    tb.buildIndex();
  }
};

ClusterCost::ClusterCost(const Eigen::MatrixX2d& A, const Eigen::MatrixX2d& B, CostOptions opt)
    : A_(A), B_(B), opt_(opt) {
  if (A_.rows() < 1 || B_.rows() < 1) throw InputError("a cluster is empty");
  if (!A_.allFinite() || !B_.allFinite()) throw InputError("a cluster has a non-finite coordinate");
  if (!(opt.trim >= 0 && opt.trim < 1)) throw UsageError("trim must be in [0, 1)");
  if (!(opt.truncate >= 0)) throw UsageError("truncate must be >= 0");
  if (opt.trim_from_data && (opt.trim > 0 || opt.truncate > 0))
    throw UsageError("a trim from the data excludes a given trim or truncation");
  cap_ = std::max(diag(A_), diag(B_));
  trees_ = std::make_unique<Trees>(A_, B_);
  // The trees' point order (leaf by leaf): neighbours in space are neighbours in it.
  order_a_.assign(trees_->ta.vAcc.begin(), trees_->ta.vAcc.end());
  order_b_.assign(trees_->tb.vAcc.begin(), trees_->tb.vAcc.end());
  // Their coordinates in that order, x y interleaved (whole-cluster queries read them in sequence).
  auto copy = [](const Eigen::MatrixX2d& P, const std::vector<int>& order, std::vector<double>& xy) {
    xy.resize(2 * order.size());
    for (size_t k = 0; k < order.size(); ++k) xy[2 * k] = P(order[k], 0), xy[2 * k + 1] = P(order[k], 1);
  };
  copy(A_, order_a_, xy_a_);
  copy(B_, order_b_, xy_b_);
}

ClusterCost::~ClusterCost() = default;

int ClusterCost::nearest_b(const double* q, double* d2) const {
  int idx = 0;
  nanoflann::KNNResultSet<double, int> rs(1);
  rs.init(&idx, d2);
  trees_->tb.findNeighbors(rs, q, nanoflann::SearchParams(10));
  return idx;
}

int ClusterCost::nearest_a(const double* q, double* d2) const {
  int idx = 0;
  nanoflann::KNNResultSet<double, int> rs(1);
  rs.init(&idx, d2);
  trees_->ta.findNeighbors(rs, q, nanoflann::SearchParams(10));
  return idx;
}

namespace {
// Maps p by H; false if it goes to infinity.
inline bool map_point(const Eigen::Matrix3d& H, double x, double y, double* q) {
  double w = H(2, 0) * x + H(2, 1) * y + H(2, 2);
  if (!(std::abs(w) > 1e-300)) return false;
  q[0] = (H(0, 0) * x + H(0, 1) * y + H(0, 2)) / w;
  q[1] = (H(1, 0) * x + H(1, 1) * y + H(1, 2)) / w;
  return std::isfinite(q[0]) && std::isfinite(q[1]) && std::abs(q[0]) < 1e150 && std::abs(q[1]) < 1e150;
}
}  // namespace

double ClusterCost::operator()(const Eigen::Matrix3d& H) const { return cost(H, opt_); }

double ClusterCost::cost(const Eigen::Matrix3d& H, const CostOptions& opt) const { return cost(H, opt, nullptr, nullptr); }

void ClusterCost::distances(const Eigen::Matrix3d& H, const Eigen::Matrix3d& Hi, const std::vector<int>* sub_a,
                            const std::vector<int>* sub_b, std::vector<double>& da, std::vector<double>& db) const {
  // Distances are stored at their point's index whatever the order of the queries, so the sums made of
  // them are those of the index order; the queries of whole clusters go in the KD-tree order (order_a()).
  auto dist = [&](const Eigen::Matrix3d& M, double x, double y, bool fwd) {
    double q[2], d2;
    if (!map_point(M, x, y, q)) return cap_ * 10;
    if (fwd)
      nearest_b(q, &d2);
    else
      nearest_a(q, &d2);
    return std::min(std::sqrt(d2), cap_ * 10);
  };
  da.clear();
  if (sub_a) {
    for (int i : *sub_a) da.push_back(dist(H, A_(i, 0), A_(i, 1), true));
  } else {
    da.resize(static_cast<size_t>(A_.rows()));
    for (size_t k = 0; k < order_a_.size(); ++k)
      da[static_cast<size_t>(order_a_[k])] = dist(H, xy_a_[2 * k], xy_a_[2 * k + 1], true);
  }
  db.clear();
  if (sub_b) {
    for (int j : *sub_b) db.push_back(dist(Hi, B_(j, 0), B_(j, 1), false));
  } else {
    db.resize(static_cast<size_t>(B_.rows()));
    for (size_t k = 0; k < order_b_.size(); ++k)
      db[static_cast<size_t>(order_b_[k])] = dist(Hi, xy_b_[2 * k], xy_b_[2 * k + 1], false);
  }
}

double ClusterCost::cost(const Eigen::Matrix3d& H, const CostOptions& opt, const std::vector<int>* sub_a,
                         const std::vector<int>* sub_b) const {
  Eigen::FullPivLU<Eigen::Matrix3d> lu(H);
  if (!H.allFinite() || !lu.isInvertible()) return std::numeric_limits<double>::infinity();
  std::vector<double> da, db;
  distances(H, lu.inverse(), sub_a, sub_b, da, db);
  return robust_mean(da, opt) + robust_mean(db, opt);
}

std::pair<double, double> ClusterCost::kept_fractions(const Eigen::Matrix3d& H) const {
  Eigen::FullPivLU<Eigen::Matrix3d> lu(H);
  if (!H.allFinite() || !lu.isInvertible()) return {0, 0};
  std::vector<double> da, db;
  distances(H, lu.inverse(), nullptr, nullptr, da, db);
  const double na = static_cast<double>(da.size()), nb = static_cast<double>(db.size());
  return {static_cast<double>(data_trim(da).keep) / na, static_cast<double>(data_trim(db).keep) / nb};
}

double ClusterCost::forward_truncated(const Eigen::Matrix3d& H, const std::vector<int>& subset, double tol) const {
  double s = 0, q[2], d2;
  for (int i : subset) {
    if (map_point(H, A_(i, 0), A_(i, 1), q)) {
      nearest_b(q, &d2);
      s += std::min(std::sqrt(d2), tol);
    } else {
      s += tol;
    }
  }
  return subset.empty() ? tol : s / static_cast<double>(subset.size());
}

std::vector<NnPair> ClusterCost::pairs(const Eigen::Matrix3d& H) const {
  std::vector<NnPair> out;
  Eigen::FullPivLU<Eigen::Matrix3d> lu(H);
  if (!H.allFinite() || !lu.isInvertible()) return out;
  Eigen::Matrix3d Hi = lu.inverse();
  out.reserve(static_cast<size_t>(A_.rows() + B_.rows()));
  // Queries in the KD-tree order (cache-friendly), results kept by index and written in index order.
  std::vector<int> nn;
  std::vector<double> dd;
  auto side = [&](const Eigen::Matrix3d& M, const Eigen::MatrixX2d& P, const std::vector<int>& order, bool fwd) {
    nn.assign(static_cast<size_t>(P.rows()), -1);
    dd.resize(static_cast<size_t>(P.rows()));
    double q[2], d2;
    for (int i : order)
      if (map_point(M, P(i, 0), P(i, 1), q)) {
        nn[static_cast<size_t>(i)] = fwd ? nearest_b(q, &d2) : nearest_a(q, &d2);
        dd[static_cast<size_t>(i)] = std::sqrt(d2);
      }
    for (size_t i = 0; i < nn.size(); ++i)
      if (nn[i] >= 0) {
        if (fwd)
          out.push_back({static_cast<int>(i), nn[i], dd[i], true});
        else
          out.push_back({nn[i], static_cast<int>(i), dd[i], false});
      }
  };
  side(H, A_, order_a_, true);
  side(Hi, B_, order_b_, false);
  return out;
}

int cluster_min_points(ClusterModel model) {
  return model == ClusterModel::Homography ? 4 : cluster_model_points(model) + 1;
}

void validate_cluster(const Eigen::MatrixX2d& pts, const std::string& source, ClusterModel model) {
  const int least = cluster_min_points(model);
  if (pts.rows() < least)
    throw InputError(source, 0, "the cluster has " + std::to_string(pts.rows()) + " point" + (pts.rows() == 1 ? "" : "s") +
                                    "; " + (model == ClusterModel::Affine ? "an " : "a ") + cluster_model_name(model) +
                                    " needs at least " + std::to_string(least));
  if (!pts.allFinite()) throw InputError(source, 0, "the cluster has a non-finite coordinate");
  Eigen::Vector2d c = pts.colwise().mean().transpose();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (Eigen::Index i = 0; i < pts.rows(); ++i) {
    Eigen::Vector2d d = pts.row(i).transpose() - c;
    cov += d * d.transpose();
  }
  double tr = cov.trace(), det = cov.determinant();
  double disc = std::sqrt(std::max(0.0, tr * tr / 4 - det));
  double lmax = tr / 2 + disc;
  double lmin = lmax > 0 ? det / lmax : 0;
  if (!(lmax > 0)) throw InputError(source, 0, "all points of the cluster coincide");
  if (!(lmin > 1e-12 * lmax)) throw InputError(source, 0, "the cluster is collinear (all points on one line); a map of the plane needs a 2-D spread");
}

double homography_max_difference(const Eigen::Matrix3d& H, const Eigen::Matrix3d& ref, const Eigen::MatrixX2d& pts) {
  double worst = 0;
  for (Eigen::Index i = 0; i < pts.rows(); ++i) {
    Eigen::Vector3d x(pts(i, 0), pts(i, 1), 1.0);
    Eigen::Vector3d a = H * x, b = ref * x;
    double e = std::hypot(a(0) / a(2) - b(0) / b(2), a(1) / a(2) - b(1) / b(2));
    if (!std::isfinite(e)) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, e);
  }
  return worst;
}

double homography_rms_difference(const Eigen::Matrix3d& H, const Eigen::Matrix3d& ref, const Eigen::MatrixX2d& pts) {
  double ss = 0;
  for (Eigen::Index i = 0; i < pts.rows(); ++i) {
    const Eigen::Vector3d x(pts(i, 0), pts(i, 1), 1.0), a = H * x, b = ref * x;
    ss += (a.head<2>() / a.z() - b.head<2>() / b.z()).squaredNorm();
  }
  const double rms = std::sqrt(ss / static_cast<double>(std::max<Eigen::Index>(1, pts.rows())));
  return std::isfinite(rms) ? rms : std::numeric_limits<double>::infinity();
}

std::vector<MutualPair> mutual_pairs(const ClusterCost& cost, const Eigen::Matrix3d& H) {
  auto pairs = cost.pairs(H);
  std::vector<int> fwd(static_cast<size_t>(cost.a().rows()), -1), bwd(static_cast<size_t>(cost.b().rows()), -1);
  std::vector<double> dist(static_cast<size_t>(cost.a().rows()), 0);
  for (const auto& p : pairs) {
    if (p.forward)
      fwd[static_cast<size_t>(p.ia)] = p.ib, dist[static_cast<size_t>(p.ia)] = p.d;
    else
      bwd[static_cast<size_t>(p.ib)] = p.ia;
  }
  std::vector<MutualPair> out;
  for (size_t i = 0; i < fwd.size(); ++i)
    if (fwd[i] >= 0 && bwd[static_cast<size_t>(fwd[i])] == static_cast<int>(i))
      out.push_back({static_cast<int>(i), fwd[i], dist[i]});
  return out;
}

}  // namespace tpkit
