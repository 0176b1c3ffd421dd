#include "tpkit/geometry/trifocal_fit.hpp"

#include <algorithm>
#include <cmath>

#include "tpkit/core/error.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/geometry/trifocal_affine_dlt.hpp"
#include "tpkit/geometry/trifocal_algebraic.hpp"
#include "tpkit/geometry/trifocal_dlt.hpp"
#include "tpkit/geometry/trifocal_minimal.hpp"
#include "tpkit/geometry/trifocal_ml.hpp"
#include "tpkit/geometry/trifocal_three_f.hpp"
#include "tpkit/geometry/trifocal_ml.hpp"

namespace tpkit {

TrifocalMethod parse_trifocal_method(const std::string& s) {
  for (TrifocalMethod m : all_trifocal_methods())
    if (trifocal_method_name(m) == s) return m;
  throw UsageError("unknown method '" + s + "' (dlt, affine-dlt, algebraic, minimal, three-f, ml)");
}

std::string trifocal_method_name(TrifocalMethod m) {
  switch (m) {
    case TrifocalMethod::Dlt: return "dlt";
    case TrifocalMethod::AffineDlt: return "affine-dlt";
    case TrifocalMethod::Algebraic: return "algebraic";
    case TrifocalMethod::Minimal: return "minimal";
    case TrifocalMethod::ThreeF: return "three-f";
    case TrifocalMethod::Ml: return "ml";
  }
  return "?";
}

const std::vector<TrifocalMethod>& all_trifocal_methods() {
  static const std::vector<TrifocalMethod> all = {TrifocalMethod::Dlt,     TrifocalMethod::AffineDlt,
                                                  TrifocalMethod::Algebraic, TrifocalMethod::Minimal,
                                                  TrifocalMethod::ThreeF,  TrifocalMethod::Ml};
  return all;
}

int trifocal_min_tracks(TrifocalMethod m) {
  switch (m) {
    case TrifocalMethod::Dlt: return kDltMinTracks;
    case TrifocalMethod::ThreeF: return kThreeFMinTracks;
    default: return kAffineMinTracks;
  }
}

TrifocalTensor run_trifocal_method(TrifocalMethod m, const Eigen::MatrixXd& xy) {
  switch (m) {
    case TrifocalMethod::Dlt: return trifocal_dlt(xy);
    case TrifocalMethod::AffineDlt: return trifocal_affine_dlt(xy);
    case TrifocalMethod::Algebraic: return trifocal_algebraic(xy);
    case TrifocalMethod::Minimal: return trifocal_minimal(xy);
    case TrifocalMethod::ThreeF: return trifocal_three_f(xy);
    case TrifocalMethod::Ml: return trifocal_ml_tensor(xy);
  }
  throw UsageError("unknown method");
}

namespace {
// A projective tensor on pixels has entries of up to the third degree in the coordinates: when the
// points lie far from the origin against their spread (offset/spread above kMaxOffsetRatio), double
// precision cannot hold it (measured: offset 1e10 px on a 256 px scene fits to 1e-5 px, 1e11 to 0.3 px,
// 1e12 to 1e6 px). The affine methods are not affected. Such input is refused, not fitted wrong.
constexpr double kMaxOffsetRatio = 1e8;
void check_projective_conditioning(const Eigen::MatrixXd& xy, const std::string& name) {
  for (int v = 0; v < 3; ++v) {
    const Eigen::MatrixXd p = xy.middleCols(2 * v, 2);
    const Eigen::RowVector2d c = p.colwise().mean();
    const double spread = std::sqrt((p.rowwise() - c).rowwise().squaredNorm().mean());
    const double offset = p.cwiseAbs().maxCoeff();
    if (!(spread > 0) || offset / spread > kMaxOffsetRatio)
      throw InputError("method " + name + ": the view " + std::to_string(v + 1) + " points lie up to " +
                       format_number(offset) + " px from the origin with a spread of " + format_number(spread) +
                       " px (ratio above 1e8): a projective tensor on these pixel coordinates cannot be held in "
                       "double precision; subtract an offset from the coordinates first, or use an affine method");
  }
}
}  // namespace

TrifocalTensor fit_trifocal(TrifocalMethod m, const Eigen::MatrixXd& xy, bool check_noise_rank) {
  const std::string name = trifocal_method_name(m);
  check_trifocal_input(xy, trifocal_min_tracks(m), name, check_noise_rank);
  if (m == TrifocalMethod::Dlt || m == TrifocalMethod::ThreeF) check_projective_conditioning(xy, name);
  TrifocalTensor T = run_trifocal_method(m, xy);
  for (const auto& Ti : T)
    if (!Ti.allFinite()) throw NumericalError("method " + name + " gave a non-finite tensor");
  return T;
}

}  // namespace tpkit

// ---- robust fitting -------------------------------------------------------------------------------


namespace tpkit {

namespace {

// Affine three-view model from minimal samples of 4 tracks (views 1..3, pixels).
class AffineTrifocalEstimator {
 public:
  using Model = AffineProjector;
  explicit AffineTrifocalEstimator(const Eigen::MatrixXd& xy) : xt_(xy.transpose()), xy_(xy) {}
  size_t size() const { return static_cast<size_t>(xt_.cols()); }
  int sample_size() const { return kMlMinTracks; }
  void generate(const std::vector<size_t>& sample, std::vector<Model>& models) const {
    Model m;
    if (fit(sample, m)) models.push_back(m);
  }
  // mean over the three views of the squared 2-D reprojection error (pixels^2)
  double error2(const Model& m, size_t i) const { return m.squared_error(xt_.col(i).data()) / 3.0; }
  bool refine(const std::vector<size_t>& inl, Model& m) const { return fit(inl, m); }

 private:
  bool fit(const std::vector<size_t>& idx, Model& m) const {
    Eigen::MatrixXd s(idx.size(), 6);
    for (size_t q = 0; q < idx.size(); ++q) s.row(q) = xy_.row(idx[q]);
    try {
      m = affine_projector(trifocal_ml(s).P);
      return m.Q.allFinite() && m.t.allFinite();
    } catch (const std::exception&) {
      return false;
    }
  }
  Eigen::Matrix<double, 6, Eigen::Dynamic> xt_;
  const Eigen::MatrixXd& xy_;
};

Eigen::MatrixXd select_rows(const Eigen::MatrixXd& xy, const std::vector<char>& mask) {
  Eigen::Index k = 0;
  for (char c : mask) k += c ? 1 : 0;
  Eigen::MatrixXd out(k, xy.cols());
  k = 0;
  for (Eigen::Index r = 0; r < xy.rows(); ++r)
    if (mask[r]) out.row(k++) = xy.row(r);
  return out;
}

}  // namespace

RobustTrifocalFit fit_trifocal_ransac(TrifocalMethod m, const Eigen::MatrixXd& xy, const RansacOptions& opt) {
  const std::string name = trifocal_method_name(m);
  check_trifocal_input(xy, std::max(trifocal_min_tracks(m), kMlMinTracks), name, false);
  if (!(opt.threshold > 0)) throw UsageError("the ransac threshold must be positive");
  AffineTrifocalEstimator est(xy);
  auto rr = ransac(est, opt);
  if (!rr.found) throw NumericalError("ransac: no sample gave a model");
  // Any 4 tracks fit the 12-parameter affine model exactly, so a model backed by its own sample alone
  // (random tracks give exactly that) or by a sliver of the data is no fit.
  const size_t n = static_cast<size_t>(xy.rows()), s = kMlMinTracks;
  const size_t need = s + std::max<size_t>(kRobustMinSupport, static_cast<size_t>(std::ceil(kRobustMinFraction * n)));
  if (rr.inliers < need)
    throw NumericalError("ransac: no fit: the best model is supported by " + std::to_string(rr.inliers) + " of " +
                         std::to_string(n) + " tracks within " + format_number(opt.threshold) + " px, its own " +
                         std::to_string(s) + "-track sample included; a fit needs at least " + std::to_string(need) +
                         " (are these tracks of one scene?)");
  RobustTrifocalFit out;
  out.iterations = rr.iterations;
  out.inlier = rr.inlier;
  out.inliers = rr.inliers;
  const Eigen::MatrixXd in = select_rows(xy, rr.inlier);
  if (in.rows() < trifocal_min_tracks(m))
    throw NumericalError("ransac: only " + std::to_string(in.rows()) + " inliers, fewer than " + name + " needs");
  out.T = fit_trifocal(m, in, true);
  return out;
}

}  // namespace tpkit
