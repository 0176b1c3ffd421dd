#include "tpkit/rpc/rpc_adjust.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <cstring>
#include <cmath>
#include <limits>
#include <memory>
#include <thread>

#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/rpc/rpc_ground.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/ground/reference_dem.hpp"

namespace tpkit {

namespace {

// The bias block as Ceres sees it: {a0, a1 * S, a2 * S, b0, b1 * S, b2 * S}, so that every term is in pixels
// over an image (S = 1000 px) and the problem is well scaled.
constexpr double kLinearScale = 1000;

ImageBias from_block(const std::array<double, 6>& p) {
  ImageBias b;
  b.a = {p[0], p[1] / kLinearScale, p[2] / kLinearScale};
  b.b = {p[3], p[4] / kLinearScale, p[5] / kLinearScale};
  return b;
}

// (projected with bias - observed) * w, w = 1 / sigma (px^-1): the weighted residual of one observation.
struct ObservationCost {
  const RpcModel* model;
  double x, y, w;
  template <typename T>
  bool operator()(const T* bias, const T* g, T* r) const {
    T p[2];
    model->project_t(g, p);
    const T u = p[0] / kLinearScale, v = p[1] / kLinearScale;
    r[0] = (p[0] + bias[0] + bias[1] * u + bias[2] * v - x) * w;
    r[1] = (p[1] + bias[3] + bias[4] * u + bias[5] * v - y) * w;
    return true;
  }
};

// A fixed image: the same residual without a bias block.
struct FixedObservationCost {
  const RpcModel* model;
  double x, y, w;
  template <typename T>
  bool operator()(const T* g, T* r) const {
    T p[2];
    model->project_t(g, p);
    r[0] = (p[0] - x) * w;
    r[1] = (p[1] - y) * w;
    return true;
  }
};

struct BiasPriorCost {
  std::array<double, 6> inv_sigma;
  template <typename T>
  bool operator()(const T* bias, T* r) const {
    for (int k = 0; k < 6; ++k) r[k] = bias[k] * inv_sigma[k];
    return true;
  }
};

// (h - H(lon, lat)) / sigma * tie_sigma0, H evaluated where the point is now (a DEM's slope moves it with
// the point).
class HeightPriorCost : public ceres::SizedCostFunction<1, 3> {
 public:
  HeightPriorCost(const HeightPrior* prior, double h_start) : prior_(prior), h_start_(h_start) {}
  bool Evaluate(double const* const* p, double* r, double** J) const override {
    const double* g = p[0];
    double h = h_start_, grad[2] = {0, 0};
    if (!prior_->at(g[0], g[1], h, grad)) grad[0] = grad[1] = 0, h = h_start_;  // stepped off the DEM: as at the start
    const double w = std::max(prior_->tie_sigma0, kMinTieSigma0) / prior_->sigma;
    r[0] = (g[2] - h) * w;
    if (J && J[0]) {
      J[0][0] = -grad[0] * w;
      J[0][1] = -grad[1] * w;
      J[0][2] = w;
    }
    return true;
  }

 private:
  const HeightPrior* prior_;
  double h_start_;
};

// A control point's ground prior: (g - known) in metres east, north, up (metres per degree of lon and lat
// at the known latitude) times w_k = s_ref / sigma_k.
struct ControlPriorCost {
  Eigen::Vector3d known, w, metres_per_degree;
  template <typename T>
  bool operator()(const T* g, T* r) const {
    for (int k = 0; k < 3; ++k) r[k] = (g[k] - known[k]) * metres_per_degree[k] * w[k];
    return true;
  }
};

// The median (upper, for an even count) of v; NaN for none.
double median_of(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// WGS 84 metres per degree of longitude and latitude at latitude lat (deg), and 1 for the height.
Eigen::Vector3d metres_per_degree(double lat) {
  const double a = 6378137.0, f = 1 / 298.257223563, e2 = f * (2 - f), rad = M_PI / 180;
  const double s = std::sin(lat * rad), w = std::sqrt(1 - e2 * s * s);
  return {a / w * std::cos(lat * rad) * rad, a * (1 - e2) / (w * w * w) * rad, 1.0};
}

class ProgressCallback : public ceres::IterationCallback {
 public:
  ProgressCallback(Progress* p) : p_(p) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (p_) p_->add();
    return ceres::SOLVER_CONTINUE;
  }

 private:
  Progress* p_;
};

std::vector<RpcObservation> observations(const std::vector<AdjustImage>& images, const std::vector<ImageBias>* bias,
                                         const AdjustTrack& t) {
  std::vector<RpcObservation> v;
  for (const auto& [i, xy] : t.views) v.push_back({&images[i].model, bias ? &(*bias)[i] : nullptr, xy});
  return v;
}

}  // namespace

void check_tracks(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks) {
  for (const auto& t : tracks) {
    const std::string id = "track " + std::to_string(t.id);
    if (t.views.size() < 2) throw InputError(t.source, t.line, id + " has fewer than two views");
    if (!t.sigma.empty() && t.sigma.size() != t.views.size())
      throw InputError(t.source, t.line, id + " has " + std::to_string(t.sigma.size()) + " sigmas for " +
                                             std::to_string(t.views.size()) + " views");
    std::vector<char> seen(images.size(), 0);
    for (size_t k = 0; k < t.views.size(); ++k) {
      const auto& [i, xy] = t.views[k];
      if (!xy.allFinite())
        throw InputError(t.source, t.line, id + ": view " + std::to_string(k + 1) + " at (" + format_number(xy[0]) + ", " +
                                               format_number(xy[1]) + ") is not a position (a view not seen is left out)");
      if (!t.sigma.empty() && (t.sigma[k] < 0 || std::isinf(t.sigma[k])))
        throw InputError(t.source, t.line, id + ": view " + std::to_string(k + 1) + " has sigma " + format_number(t.sigma[k]) +
                                               " (a standard deviation in pixels: >= 0, or nan when not known)");
      if (i < 0 || i >= static_cast<int>(images.size())) throw InputError(t.source, t.line, id + " names an image out of range");
      if (seen[i]++) throw InputError(t.source, t.line, id + " views " + images[i].path + " twice");
      const AdjustImage& im = images[i];
      // a tie point lies on its image (a pixel's edge is 0.5 px from its centre; one more pixel of slack)
      if (im.width > 0 && !(xy[0] >= -1.5 && xy[0] <= im.width + 0.5 && xy[1] >= -1.5 && xy[1] <= im.height + 0.5))
        throw InputError(t.source, t.line, id + ": view " + std::to_string(k + 1) + " at (" + format_number(xy[0]) + ", " +
                                               format_number(xy[1]) + ") is off " + im.path + " (" + std::to_string(im.width) +
                                               " x " + std::to_string(im.height) + " pixels)");
    }
  }
  if (tracks.empty()) throw NumericalError("no tracks to adjust the RPCs with");
}

namespace {

// Initial ground points: the zero-bias least-squares intersection of every track.
void initial_points(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                    const AdjustOptions& o, AdjustResult& r) {
  const size_t n = tracks.size();
  r.ground.assign(n, Eigen::Vector3d::Zero());
  r.rms_before.assign(n, std::numeric_limits<double>::quiet_NaN());
  r.initial_ok.assign(n, 0);
  parallel_for(n, o.threads, [&](size_t t) {
    auto v = observations(images, nullptr, tracks[t]);
    double h0 = NAN;
    if (o.height.at) {
      const RpcModel& m = images[tracks[t].views[0].first].model;
      try {
        Eigen::Vector2d ll = m.localize(v[0].xy[0], v[0].xy[1], m.height_off);
        double h;
        if (o.height.at(ll[0], ll[1], h, nullptr)) h0 = h;
      } catch (const NumericalError&) {
      }
    }
    RpcIntersection x = intersect_rpc(v, h0);
    if (x.ok) {
      r.ground[t] = x.llh;
      r.rms_before[t] = x.rms_px;
      r.initial_ok[t] = 1;
    }
  });
}

}  // namespace

namespace {

// The views of a track that are in the fit: keep[k] per view of tracks[t].
using ViewMask = std::vector<std::vector<char>>;

std::vector<RpcObservation> kept_observations(const std::vector<AdjustImage>& images, const std::vector<ImageBias>* bias,
                                              const AdjustTrack& t, const std::vector<char>& keep) {
  std::vector<RpcObservation> v;
  for (size_t k = 0; k < t.views.size(); ++k)
    if (keep[k]) v.push_back({&images[t.views[k].first].model, bias ? &(*bias)[t.views[k].first] : nullptr, t.views[k].second});
  return v;
}

// The per-view blunders (see the header), decided afresh on the current biases: each track of 3 or more
// views whose RMS over all of them, re-intersected on the adjusted models, is above flag_px loses views
// one at a time (the one whose removal leaves the smallest RMS) while it stays above flag_px, at most
// (n - 1) / 2 of its n views; the drops are taken only when what remains is under flag_px and the last
// drop is not ambiguous (no other removal within twice its RMS); every other track keeps all its views (a
// drop decided on the biases of a fit that still held the blunders may be undone). Returns the number
// of views whose state changed.
long drop_blunder_views(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks, const AdjustResult& r,
                        double flag_px, int threads, ViewMask& keep) {
  const size_t nt = tracks.size();
  std::vector<std::vector<char>> next(nt);
  parallel_for(nt, threads, [&](size_t t) {
    const size_t n = tracks[t].views.size();
    std::vector<char> k(n, 1);
    next[t] = k;
    if (!r.initial_ok[t] || n < 3) return;
    const RpcIntersection all = intersect_rpc(kept_observations(images, &r.bias, tracks[t], k), r.ground[t][2]);
    if (all.ok && all.rms_px <= flag_px) return;
    long dropped = 0;
    while (true) {
      if (std::count(k.begin(), k.end(), 1) < 3 || dropped + 1 > static_cast<long>(n - 1) / 2) return;
      double best = std::numeric_limits<double>::infinity(), second = best;
      size_t best_view = 0;
      for (size_t j = 0; j < n; ++j) {
        if (!k[j]) continue;
        k[j] = 0;
        const RpcIntersection x = intersect_rpc(kept_observations(images, &r.bias, tracks[t], k), r.ground[t][2]);
        k[j] = 1;
        if (!x.ok) continue;
        if (x.rms_px < best) second = best, best = x.rms_px, best_view = j;
        else if (x.rms_px < second) second = x.rms_px;
      }
      if (!std::isfinite(best)) return;
      k[best_view] = 0;
      ++dropped;
      // the last drop must name its view: another removal that fits as well (a blunder along the
      // epipolar line of the pair it leaves) leaves the track flagged
      if (best <= flag_px) {
        if (second <= flag_px && second <= 2 * best) return;
        break;
      }
    }
    next[t] = std::move(k);
  });
  long changed = 0;
  for (size_t t = 0; t < nt; ++t) {
    for (size_t j = 0; j < next[t].size(); ++j) changed += keep[t][j] != next[t][j];
    keep[t] = std::move(next[t]);
  }
  return changed;
}

}  // namespace

AdjustResult adjust_rpcs(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                         const AdjustOptions& o) {
  check_tracks(images, tracks);
  AdjustResult r;
  initial_points(images, tracks, o, r);
  long usable = std::count(r.initial_ok.begin(), r.initial_ok.end(), 1);
  if (usable == 0) throw NumericalError("no track could be intersected with the given RPCs (do the images overlap?)");

  const size_t ni = images.size(), nt = tracks.size();
  std::vector<std::array<double, 6>> block(ni, std::array<double, 6>{});
  auto used = bias_terms_used(o.model);
  std::vector<int> constant_terms;
  for (int k = 0; k < 6; ++k)
    if (!used[k]) constant_terms.push_back(k);
  // each observation's sigma (px): given (floored), else the default
  std::vector<double> given;
  if (o.use_sigma)
    for (size_t t = 0; t < nt; ++t)
      if (r.initial_ok[t])
        for (double s : tracks[t].sigma)
          if (std::isfinite(s)) given.push_back(std::max(s, kMinObservationSigma));
  r.obs_with_sigma = static_cast<long>(given.size());
  if (std::isfinite(o.default_sigma_px)) {
    if (!(o.default_sigma_px > 0)) throw UsageError("the default sigma of an observation must be positive (pixels)");
    r.default_sigma_px = std::max(o.default_sigma_px, kMinObservationSigma);
  } else if (!given.empty()) {
    std::nth_element(given.begin(), given.begin() + given.size() / 2, given.end());
    r.default_sigma_px = given[given.size() / 2];
  } else {
    r.default_sigma_px = 1;
  }
  auto sigma_of = [&](const AdjustTrack& t, size_t k) {
    if (o.use_sigma && !t.sigma.empty() && std::isfinite(t.sigma[k])) return std::max(t.sigma[k], kMinObservationSigma);
    return r.default_sigma_px;
  };
  // the reference sigma: the median over the observations; weights are s_ref / sigma (see the header)
  {
    std::vector<double> all;
    for (size_t t = 0; t < nt; ++t)
      if (r.initial_ok[t])
        for (size_t k = 0; k < tracks[t].views.size(); ++k) all.push_back(sigma_of(tracks[t], k));
    std::nth_element(all.begin(), all.begin() + all.size() / 2, all.end());
    r.reference_sigma_px = all[all.size() / 2];
  }
  const double s_ref = r.reference_sigma_px;
  ViewMask keep(nt);
  for (size_t t = 0; t < nt; ++t) keep[t].assign(tracks[t].views.size(), 1);
  // the zero-bias points (the fit moves r.ground): the residuals "before"
  std::vector<Eigen::Vector3d> before(nt);
  for (size_t t = 0; t < nt; ++t) before[t] = r.ground[t];
  r.control_ground.resize(o.control.size());
  for (size_t c = 0; c < o.control.size(); ++c) r.control_ground[c] = o.control[c].llh;

  // One solve over the kept views, started from r.ground, block and r.control_ground.
  auto solve = [&]() {
    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    std::vector<char> image_seen(ni, 0);
    long with_height = 0;
    for (size_t t = 0; t < nt; ++t) {
      if (!r.initial_ok[t]) continue;
      double* g = r.ground[t].data();
      for (size_t k = 0; k < tracks[t].views.size(); ++k) {
        if (!keep[t][k]) continue;
        const auto& [i, xy] = tracks[t].views[k];
        image_seen[i] = 1;
        const double w = s_ref / sigma_of(tracks[t], k);
        // Huber on the weighted residual at loss_px * w: linear where the pixel residual exceeds loss_px
        ceres::LossFunction* loss = new ceres::HuberLoss(o.loss_px * w);
        if (images[i].fixed) {
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<FixedObservationCost, 2, 3>(
                                       new FixedObservationCost{&images[i].model, xy[0], xy[1], w}),
                                   loss, g);
        } else {
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ObservationCost, 2, 6, 3>(
                                       new ObservationCost{&images[i].model, xy[0], xy[1], w}),
                                   loss, block[i].data(), g);
        }
      }
      if (o.height.at) {
        double h;
        if (o.height.at(r.ground[t][0], r.ground[t][1], h, nullptr)) {
          // robust (Huber, HeightPrior::loss sigmas): a tree top or a roof edge pulls with a bounded force
          problem.AddResidualBlock(new HeightPriorCost(&o.height, h),
                                   o.height.loss > 0 ? new ceres::HuberLoss(o.height.loss * std::max(o.height.tie_sigma0, kMinTieSigma0)) : nullptr, g);
          ++with_height;
        }
      }
    }
    // ground control points: an unknown ground point each, with its prior and its measurements (no loss)
    for (size_t c = 0; c < o.control.size(); ++c) {
      const AdjustControl& gc = o.control[c];
      double* g = r.control_ground[c].data();
      const Eigen::Vector3d w = Eigen::Vector3d::Constant(s_ref).cwiseQuotient(gc.sigma_enu);
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ControlPriorCost, 3, 3>(
                                   new ControlPriorCost{gc.llh, w, metres_per_degree(gc.llh[1])}),
                               nullptr, g);
      for (size_t k = 0; k < gc.views.size(); ++k) {
        const auto& [i, xy] = gc.views[k];
        image_seen[i] = 1;
        const double wk = s_ref / std::max(gc.sigma_px[k], kMinObservationSigma);
        if (images[i].fixed)
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<FixedObservationCost, 2, 3>(
                                       new FixedObservationCost{&images[i].model, xy[0], xy[1], wk}),
                                   nullptr, g);
        else
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ObservationCost, 2, 6, 3>(
                                       new ObservationCost{&images[i].model, xy[0], xy[1], wk}),
                                   nullptr, block[i].data(), g);
      }
    }
    if (o.height.at && with_height == 0)
      throw NumericalError("the height prior reaches none of the " + std::to_string(usable) +
                           " tie points (a DEM off the scene, or only no-data where they are)");
    BiasPriorCost prior;
    for (int k = 0; k < 6; ++k)
      prior.inv_sigma[k] = 1.0 / (k % 3 == 0 ? o.prior_shift_px : o.prior_linear * kLinearScale);
    for (size_t i = 0; i < ni; ++i) {
      if (images[i].fixed || !image_seen[i]) continue;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<BiasPriorCost, 6, 6>(new BiasPriorCost(prior)), nullptr,
                               block[i].data());
      if (!constant_terms.empty())
        problem.SetManifold(block[i].data(), new ceres::SubsetManifold(6, constant_terms));
    }

    ceres::Solver::Options so;
    so.linear_solver_type = ni <= 200 ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
    // Ceres aborts on a thread it cannot start, and warns on stderr (glog) beyond the machine's cores
    const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    so.num_threads = o.threads > 1 ? std::min(startable_threads(o.threads), cores) : 1;
    so.max_num_iterations = o.max_iterations;
    so.function_tolerance = 1e-12;
    so.gradient_tolerance = 1e-14;
    so.parameter_tolerance = 1e-12;
    so.logging_type = ceres::SILENT;
    std::unique_ptr<Progress> progress;
    if (o.progress) progress = std::make_unique<Progress>("rpc-adjust: iterations", o.max_iterations);
    ProgressCallback cb(progress.get());
    so.callbacks.push_back(&cb);
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    if (progress) progress->done();
    r.iterations += static_cast<int>(summary.iterations.size());
    r.converged = summary.termination_type == ceres::CONVERGENCE;
    r.solver_report = summary.BriefReport();
    if (!summary.IsSolutionUsable()) throw NumericalError("the adjustment failed: " + summary.BriefReport());
    if (!std::isfinite(summary.initial_cost) || !std::isfinite(summary.final_cost))
      throw NumericalError("the adjustment's cost is not finite (initial " + format_figure(summary.initial_cost) +
                           "): an observation or a prior sigma is out of range");
    r.bias.resize(ni);
    for (size_t i = 0; i < ni; ++i) r.bias[i] = images[i].fixed ? ImageBias{} : from_block(block[i]);
  };

  // residuals before (zero bias, initial points) and after, per observation and per track; a track's RMS
  // after is over its kept views
  double sum = 0, wsum = 0;
  long count = 0;
  auto residuals = [&]() {
    r.rms_after.assign(nt, std::numeric_limits<double>::quiet_NaN());
    r.flagged.assign(nt, 0);
    r.views_dropped.assign(nt, 0);
    r.obs_track.clear(), r.obs_image.clear(), r.obs_xy.clear(), r.res_before.clear(), r.res_after.clear();
    r.obs_sigma.clear(), r.obs_dropped.clear();
    sum = wsum = 0;
    count = 0;
    for (size_t t = 0; t < nt; ++t) {
      if (!r.initial_ok[t]) continue;
      auto v0 = observations(images, nullptr, tracks[t]);
      auto v = observations(images, &r.bias, tracks[t]);
      double s = 0;
      long n = 0;
      for (size_t k = 0; k < v.size(); ++k) {
        Eigen::Vector2d e0 = rpc_observe(v0[k], before[t]) - v0[k].xy;
        Eigen::Vector2d e1 = rpc_observe(v[k], r.ground[t]) - v[k].xy;
        r.obs_track.push_back(static_cast<int>(t));
        r.obs_image.push_back(tracks[t].views[k].first);
        r.obs_xy.push_back(v[k].xy);
        r.res_before.push_back(e0);
        r.res_after.push_back(e1);
        const double sg = sigma_of(tracks[t], k);
        r.obs_sigma.push_back(sg);
        r.obs_dropped.push_back(!keep[t][k]);
        if (!keep[t][k]) {
          ++r.views_dropped[t];
          continue;
        }
        wsum += e1.squaredNorm() * (s_ref * s_ref) / (sg * sg);
        s += e1.squaredNorm();
        ++n;
      }
      sum += s;
      count += n;
      r.rms_after[t] = std::sqrt(s / n);
      r.flagged[t] = r.rms_after[t] > o.flag_px;
    }
  };

  r.iterations = 0;
  solve();
  for (size_t t = 0; t < nt; ++t) {
    if (!r.initial_ok[t]) continue;
    RpcIntersection x0 = intersect_rpc(observations(images, nullptr, tracks[t]));  // the zero-bias point again
    if (x0.ok) before[t] = x0.llh;
  }
  residuals();
  // per-view blunders: drop, solve again from the last solution, until the views dropped stay the same
  // (three rounds at most)
  for (int round = 0; o.drop_views && round < 3; ++round) {
    if (drop_blunder_views(images, tracks, r, o.flag_px, o.threads, keep) == 0) break;
    ++r.drop_rounds;
    solve();
    residuals();
  }
  r.dropped_views = std::count(r.obs_dropped.begin(), r.obs_dropped.end(), 1);
  r.tracks_with_dropped = std::count_if(r.views_dropped.begin(), r.views_dropped.end(), [](int d) { return d > 0; });
  r.sigma0 = std::sqrt(sum / std::max(1L, 2 * count));
  r.sigma0_weighted = std::sqrt(wsum / std::max(1L, 2 * count));
  if (!o.keep_untrusted)
    if (const FitTrust trust = fit_trust(images, tracks, r, o.flag_px); !trust.ok()) throw NumericalError(trust.message());
  // sigma_h: the weighted normal matrix of the point, (J^T W J)^-1 (h, h) scaled by the a posteriori
  // variance of unit weight, W = (s_ref / sigma)^2 (unit weights: sigma0^2 (J^T J)^-1, as tp-ground's)
  r.sigma_h.assign(nt, std::numeric_limits<double>::quiet_NaN());
  for (size_t t = 0; t < nt; ++t) {
    if (!r.initial_ok[t]) continue;
    auto v = observations(images, &r.bias, tracks[t]);
    Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
    for (size_t k = 0; k < v.size(); ++k) {
      if (!keep[t][k]) continue;
      Eigen::Matrix<double, 2, 3> J;
      rpc_observe(v[k], r.ground[t], &J);
      const double sg = sigma_of(tracks[t], k);
      N += J.transpose() * J * (s_ref * s_ref) / (sg * sg);
    }
    Eigen::Vector3d d = N.diagonal().cwiseSqrt().cwiseMax(1e-300).cwiseInverse();
    Eigen::Matrix3d C = d.asDiagonal() * (d.asDiagonal() * N * d.asDiagonal()).inverse() * d.asDiagonal();
    r.sigma_h[t] = r.sigma0_weighted * std::sqrt(std::max(C(2, 2), 0.0));
  }
  return r;
}


FitTrust fit_trust(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks, const AdjustResult& r,
                   double flag_px) {
  FitTrust trust;
  const long usable = std::count(r.initial_ok.begin(), r.initial_ok.end(), 1);
  const long flagged = std::count(r.flagged.begin(), r.flagged.end(), 1);
  if (2 * flagged >= usable) {
    trust.figures = std::to_string(flagged) + " of " + std::to_string(usable) + " tracks keep an RMS above " + format_figure(flag_px) +
                    " px after the fit (rms " + format_figure(residual_rms(r, false)) + " px before, " +
                    format_figure(residual_rms(r, true)) + " px after, " + std::to_string(r.iterations) + " iterations)";
    trust.cause = "wrong models, wrong tracks, or a --flag too tight";
    return trust;
  }
  // per image: the tracks that view it, those flagged, and those kept that lost its view as a blunder (a
  // wrong model would otherwise lose its every view of a long track and pass)
  std::vector<long> seen(images.size(), 0), bad(images.size(), 0), dropped(images.size(), 0);
  for (size_t t = 0; t < tracks.size(); ++t)
    if (r.initial_ok[t])
      for (const auto& [i, xy] : tracks[t].views) ++seen[i], bad[i] += r.flagged[t];
  for (size_t k = 0; k < r.obs_dropped.size() && k < r.obs_track.size(); ++k)
    if (r.obs_dropped[k] && !r.flagged[static_cast<size_t>(r.obs_track[k])]) ++dropped[r.obs_image[k]], ++bad[r.obs_image[k]];
  for (size_t i = 0; i < images.size(); ++i)
    if (bad[i] > 0 && 2 * bad[i] >= seen[i]) {
      trust.figures = "image" + std::to_string(i + 1) + " " + images[i].path + ": " + std::to_string(bad[i]) + " of the " +
                      std::to_string(seen[i]) + " tracks that view it keep an RMS above " + format_figure(flag_px) +
                      " px after the fit" +
                      (dropped[i] ? " or lost that view as a blunder (" + std::to_string(dropped[i]) + ")" : std::string()) +
                      " (its rms " + format_figure(residual_rms(r, false, static_cast<int>(i))) + " px before, " +
                      format_figure(residual_rms(r, true, static_cast<int>(i))) + " px after)";
      trust.cause = "its model does not fit them where the other images' do (another image's model, or one that diverges over "
                    "the image, which no bias model follows), or its tracks are wrong";
      return trust;
    }
  return trust;
}

double inlier_rms(const AdjustResult& r, int image) {
  double s = 0;
  long n = 0;
  for (size_t k = 0; k < r.obs_track.size(); ++k) {
    if (r.flagged[static_cast<size_t>(r.obs_track[k])] || (image >= 0 && r.obs_image[k] != image)) continue;
    if (k < r.obs_dropped.size() && r.obs_dropped[k]) continue;
    s += r.res_after[k].squaredNorm();
    ++n;
  }
  return n ? std::sqrt(s / static_cast<double>(n)) : std::numeric_limits<double>::quiet_NaN();
}

double residual_rms(const AdjustResult& r, bool after, int image) {
  double s = 0;
  long n = 0;
  for (size_t k = 0; k < r.obs_image.size(); ++k) {
    if (image >= 0 && r.obs_image[k] != image) continue;
    s += (after ? r.res_after[k] : r.res_before[k]).squaredNorm();
    ++n;
  }
  return n ? std::sqrt(s / n) : std::numeric_limits<double>::quiet_NaN();
}

std::map<int, long> tracks_by_length(const std::vector<AdjustTrack>& tracks, const AdjustResult& r) {
  std::map<int, long> out;
  for (size_t t = 0; t < tracks.size() && t < r.initial_ok.size(); ++t)
    if (r.initial_ok[t]) ++out[static_cast<int>(tracks[t].views.size())];
  return out;
}

std::string format_lengths(const std::map<int, long>& by_length) {
  std::string s;
  for (const auto& [len, n] : by_length) s += (s.empty() ? "" : " ") + std::to_string(len) + ":" + std::to_string(n);
  return s.empty() ? "none" : s;
}

std::vector<ImageReport> image_reports(size_t images, const std::vector<AdjustTrack>& tracks, const AdjustResult& r) {
  std::vector<ImageReport> out(images);
  for (size_t t = 0; t < tracks.size() && t < r.initial_ok.size(); ++t)
    if (r.initial_ok[t])
      for (const auto& [i, xy] : tracks[t].views) ++out[i].tracks_by_length[static_cast<int>(tracks[t].views.size())];
  std::vector<std::vector<double>> sigmas(images);
  for (size_t k = 0; k < r.obs_image.size(); ++k) {
    ++out[r.obs_image[k]].observations;
    if (k < r.obs_sigma.size()) sigmas[r.obs_image[k]].push_back(r.obs_sigma[k]);
  }
  for (size_t i = 0; i < images; ++i) {
    out[i].rms_before = residual_rms(r, false, static_cast<int>(i));
    out[i].rms_after = residual_rms(r, true, static_cast<int>(i));
    out[i].rms_after_unflagged = inlier_rms(r, static_cast<int>(i));
    auto& v = sigmas[i];
    if (v.empty()) {
      out[i].median_sigma = std::numeric_limits<double>::quiet_NaN();
    } else {
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      out[i].median_sigma = v[v.size() / 2];
    }
  }
  return out;
}

HeightPriorSpread height_prior_spread(const HeightPrior& prior, const AdjustResult& free_fit) {
  HeightPriorSpread sp;
  std::vector<double> dh, sh;
  for (size_t t = 0; t < free_fit.ground.size(); ++t) {
    if (!free_fit.initial_ok[t] || (t < free_fit.flagged.size() && free_fit.flagged[t])) continue;
    double h;
    const Eigen::Vector3d& g = free_fit.ground[t];
    if (!prior.at || !prior.at(g[0], g[1], h, nullptr)) continue;
    dh.push_back(h - g[2]);
    if (t < free_fit.sigma_h.size() && std::isfinite(free_fit.sigma_h[t])) sh.push_back(free_fit.sigma_h[t]);
  }
  sp.covered = static_cast<long>(dh.size());
  if (dh.empty()) return sp;
  sp.median_dh = median_of(dh);
  std::vector<double> dev;
  for (double d : dh) dev.push_back(std::fabs(d - sp.median_dh));
  sp.nmad_dh = 1.4826 * median_of(dev);
  sp.median_sigma_h = median_of(sh);
  return sp;
}

double estimated_height_sigma(const HeightPriorSpread& sp) {
  double s = kMinEstimatedHeightSigma;
  if (std::isfinite(sp.nmad_dh)) s = std::max(s, sp.nmad_dh);
  if (std::isfinite(sp.median_sigma_h)) s = std::max(s, kPriorPrecisionRatio * sp.median_sigma_h);
  return s;
}

double delivered_bias_bound_px(const AdjustImage& im) {
  double limit = kGroundMaxBiasPx;
  const double stated = std::hypot(std::max(0.0, im.model.err_bias), std::max(0.0, im.model.err_rand));
  const double gsd = model_gsd(im.model, im.width, im.height);
  if (stated > 0 && std::isfinite(gsd) && gsd > 0) limit = std::max(limit, kGroundStatedErrors * stated / gsd);
  return limit;
}

HeightPriorCheck check_height_prior(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                                    const AdjustOptions& options, const AdjustResult& with_prior, const AdjustResult* given_free) {
  HeightPriorCheck c;
  c.sigma = options.height.sigma;
  AdjustResult own_free;
  if (!given_free) {
    AdjustOptions free_options = options;
    free_options.height = HeightPrior{};
    free_options.progress = false;
    free_options.keep_untrusted = false;  // a free fit that fails too: the models or the tracks are wrong
    own_free = adjust_rpcs(images, tracks, free_options);
  }
  const AdjustResult& free_fit = given_free ? *given_free : own_free;
  // the RMS of both fits over the same observations: those of the tracks that neither fit flags nor
  // dropped a view of, so that a few blunders (whose residuals grow when a prior holds their heights) do
  // not pass for a contradiction; the blunders are compared by their count
  c.flagged_with = std::count(with_prior.flagged.begin(), with_prior.flagged.end(), 1);
  c.flagged_without = std::count(free_fit.flagged.begin(), free_fit.flagged.end(), 1);
  auto out_of_common = [&](size_t t) {
    auto lost = [&](const AdjustResult& r) { return t < r.views_dropped.size() && r.views_dropped[t] > 0; };
    return with_prior.flagged[t] || free_fit.flagged[t] || lost(with_prior) || lost(free_fit);
  };
  auto common_rms = [&](const AdjustResult& r) {
    double s = 0;
    long n = 0;
    for (size_t k = 0; k < r.obs_track.size(); ++k) {
      const size_t t = static_cast<size_t>(r.obs_track[k]);
      if (out_of_common(t)) continue;
      s += r.res_after[k].squaredNorm();
      ++n;
    }
    c.common_tracks = 0;
    for (size_t t = 0; t < r.flagged.size(); ++t) c.common_tracks += r.initial_ok[t] && !out_of_common(t);
    return n ? std::sqrt(s / static_cast<double>(n)) : std::numeric_limits<double>::quiet_NaN();
  };
  c.rms_with = common_rms(with_prior);
  c.rms_without = common_rms(free_fit);
  const long more_flagged = static_cast<long>(c.flagged_with) - static_cast<long>(c.flagged_without);
  const HeightPriorSpread sp = height_prior_spread(options.height, free_fit);
  std::vector<double> adh;
  for (size_t t = 0; t < free_fit.ground.size(); ++t) {
    if (!free_fit.initial_ok[t] || free_fit.flagged[t]) continue;
    double h;
    const Eigen::Vector3d& g = free_fit.ground[t];
    if (options.height.at && options.height.at(g[0], g[1], h, nullptr)) adh.push_back(std::fabs(h - g[2]));
  }
  c.covered = sp.covered;
  c.median_dh = sp.median_dh;
  c.nmad_dh = sp.nmad_dh;
  c.median_abs_dh = median_of(adh);
  // the level: the free fit's is the delivered models' (a fixed image's, or the smallest biases'); a prior is
  // there to correct it, and contradicts only beyond its own spread and by biases no delivered model has
  c.level_limit = 3 * estimated_height_sigma(sp);
  for (size_t i = 0; i < images.size() && i < with_prior.bias.size() && i < free_fit.bias.size(); ++i) {
    const Eigen::Vector2d centre(0.5 * (images[i].width - 1), 0.5 * (images[i].height - 1));
    const double d = (with_prior.bias[i].offset(centre) - free_fit.bias[i].offset(centre)).norm();
    if (c.forced_image < 0 || d / delivered_bias_bound_px(images[i]) > c.forced_bias_px / c.bias_bound_px)
      c.forced_bias_px = d, c.forced_image = static_cast<int>(i), c.bias_bound_px = delivered_bias_bound_px(images[i]);
  }
  // The RMS may grow by what a prior of the tie points' own precision would cost: a quarter of their
  // reference sigma (not a fixed 0.02 px: a 2 m DEM against noise-free tracks costs 0.05-0.09 px).
  c.impossible = c.covered > 0 && std::fabs(c.median_dh) > c.level_limit && c.forced_bias_px > c.bias_bound_px;
  c.contradicts = c.rms_with > 1.2 * c.rms_without + 0.25 * with_prior.reference_sigma_px || c.impossible ||
                  more_flagged > std::max<long>(10, static_cast<long>(free_fit.flagged.size() / 100));
  c.figures = "rms after " + format_figure(c.rms_with) + " px with it, " + format_figure(c.rms_without) + " px without (over the " +
              std::to_string(c.common_tracks) + " tracks neither flags); flagged tracks " +
              std::to_string(c.flagged_with) + " with, " + std::to_string(c.flagged_without) + " without; prior minus free height: median " +
              format_figure(c.median_dh) + " m (3 NMAD " + format_figure(c.level_limit) + " m; the biases it forces: " +
              format_figure(c.forced_bias_px) + " px at image" + std::to_string(c.forced_image + 1) + ", a delivered model's at most " +
              format_figure(c.bias_bound_px) + " px), NMAD " +
              format_figure(c.nmad_dh) + " m, median |.| " + format_figure(c.median_abs_dh) + " m = " +
              format_figure(c.median_abs_dh / c.sigma) + " sigma (sigma " + format_figure(c.sigma) + " m, " + std::to_string(c.covered) + " tracks)";
  return c;
}

std::vector<AdjustControl> gcps_to_adjust(const std::vector<Gcp>& gcps, GcpRole role, const std::vector<AdjustImage>& images) {
  std::vector<std::string> paths;
  for (const auto& im : images) paths.push_back(im.path);
  std::vector<AdjustControl> out;
  for (const Gcp& g : gcps) {
    if (g.role != role) continue;
    AdjustControl c;
    c.source = g.source;
    c.line = g.line;
    c.id = g.id;
    c.llh = g.llh;
    c.sigma_enu = g.sigma_enu;
    const std::string id = (role == GcpRole::control ? "control point " : "check point ") + std::to_string(g.id);
    for (const GcpMeasurement& m : g.measurements) {
      const int i = image_index(m.image, paths, g.source);
      if (i < 0)
        throw InputError(g.source, m.line, id + ": image '" + m.image + "' is " + (i == -2 ? "ambiguous among" : "not one of") + " the images given");
      const AdjustImage& im = images[i];
      if (im.width > 0 && !(m.xy[0] >= -0.5 && m.xy[0] <= im.width - 0.5 && m.xy[1] >= -0.5 && m.xy[1] <= im.height - 0.5))
        throw InputError(g.source, m.line, id + ": (" + format_number(m.xy[0]) + ", " + format_number(m.xy[1]) + ") is off " +
                                               im.path + " (" + std::to_string(im.width) + " x " + std::to_string(im.height) + " pixels)");
      for (const auto& v : c.views)
        if (v.first == i) throw InputError(g.source, m.line, id + " is measured twice in " + im.path);
      c.views.emplace_back(i, m.xy);
      c.sigma_px.push_back(m.sigma_px);
      c.view_line.push_back(m.line);
    }
    if (role == GcpRole::control && c.views.empty())
      throw InputError(g.source, g.line, id + " is measured in no image: it cannot hold the adjustment");
    if (role == GcpRole::check && c.views.size() < 2)
      throw InputError(g.source, g.line, id + " is measured in " + std::to_string(c.views.size()) +
                                             " image(s): a check point is intersected from two or more");
    out.push_back(std::move(c));
  }
  return out;
}

ControlEvaluation evaluate_controls(const std::vector<AdjustImage>& images, const std::vector<ImageBias>* bias,
                                    const std::vector<AdjustControl>& points) {
  ControlEvaluation e;
  for (const auto& p : points) {
    std::vector<RpcObservation> v;
    for (const auto& [i, xy] : p.views) v.push_back({&images[i].model, bias ? &(*bias)[i] : nullptr, xy});
    RpcIntersection x;
    if (v.size() >= 2) x = intersect_rpc(v, p.llh[2]);
    e.intersection.push_back(x);
    std::vector<Eigen::Vector2d> res;
    for (const auto& o : v) res.push_back(rpc_observe(o, p.llh) - o.xy);
    e.known_residual_px.push_back(res);
  }
  return e;
}

GcpModelCheck check_gcps_on_models(const std::vector<AdjustImage>& images, const std::vector<AdjustControl>& points) {
  GcpModelCheck c;
  const ControlEvaluation e = evaluate_controls(images, nullptr, points);
  std::vector<double> dx, dy, de, dn, du, lon, lat;
  for (size_t p = 0; p < points.size(); ++p) {
    const AdjustControl& g = points[p];
    double s = 0;
    for (size_t k = 0; k < g.views.size(); ++k) {
      const Eigen::Vector2d& r = e.known_residual_px[p][k];
      s += r.squaredNorm();
      dx.push_back(r[0]);
      dy.push_back(r[1]);
      const auto& [i, xy] = g.views[k];
      try {
        const Eigen::Vector2d ll = images[i].model.localize(xy[0], xy[1], g.llh[2]);
        const Eigen::Vector3d m = metres_per_degree(g.llh[1]);
        de.push_back((g.llh[0] - ll[0]) * m[0]);
        dn.push_back((g.llh[1] - ll[1]) * m[1]);
      } catch (const NumericalError&) {  // not localized: its pixel offset still counts
      }
    }
    c.measurements += static_cast<long>(g.views.size());
    c.residual_px.push_back(g.views.empty() ? 0.0 : std::sqrt(s / g.views.size()));
    if (c.residual_px.back() > c.worst_px) c.worst_px = c.residual_px.back(), c.worst_id = g.id;
    if (e.intersection[p].ok) du.push_back(g.llh[2] - e.intersection[p].llh[2]);
    lon.push_back(g.llh[0]);
    lat.push_back(g.llh[1]);
  }
  c.points = static_cast<long>(points.size());
  c.intersected = static_cast<long>(du.size());
  if (points.empty()) return c;
  c.median_px = median_of(c.residual_px);
  c.offset_px = {median_of(dx), median_of(dy)};
  c.offset_en = {median_of(de), median_of(dn)};
  c.offset_u = median_of(du);
  std::vector<double> spread;
  for (double d : du) spread.push_back(std::fabs(d - c.offset_u));
  c.spread_u = median_of(spread);
  try {
    const VerticalDatum egm96("egm96", "the GCPs' geoid check");
    c.geoid_n = egm96.undulation(median_of(lon), median_of(lat));
  } catch (const InputError&) {  // no grid: the heights are still compared, the geoid not named
  }
  const double tol = std::max(5.0, 0.2 * std::fabs(c.geoid_n));
  c.geoid_like = std::fabs(c.geoid_n) >= 15 && std::fabs(std::fabs(c.offset_u) - std::fabs(c.geoid_n)) <= tol && c.spread_u <= tol;
  if (c.median_px > kGcpWarnPx)
    c.problem = "the points lie " + format_figure(c.median_px) + " px (median) from where the delivered models project them, "
                "beyond those models' error of a few to a few tens of pixels (a wrong zone, datum or coordinate order?)";
  c.refuse = c.median_px > kGcpRefusePx;
  if (c.geoid_like)
    c.problem += std::string(c.problem.empty() ? "" : "; ") + "their heights lie " + format_figure(std::fabs(c.offset_u)) + " m " +
                 (c.offset_u < 0 ? "below" : "above") + " those the delivered models intersect them at, the geoid undulation there (" +
                 format_figure(c.geoid_n) + " m): " +
                 (c.offset_u < 0 ? "geoid heights given as ellipsoidal?" : "ellipsoidal heights given as geoid heights?");
  c.figures = std::to_string(c.points) + " points, " + std::to_string(c.measurements) +
              " measurements: projection of the known position minus the measurement, median over the points " +
              format_figure(c.median_px) + " px (largest " + format_figure(c.worst_px) + " px at point " + std::to_string(c.worst_id) +
              "), offset " + format_figure(c.offset_px[0]) + ", " + format_figure(c.offset_px[1]) + " px = known minus seen " +
              format_figure(c.offset_en[0]) + " m east, " + format_figure(c.offset_en[1]) + " m north";
  if (c.intersected > 0)
    c.figures += "; known minus intersected height, median over " + std::to_string(c.intersected) + " points " +
                 format_figure(c.offset_u) + " m (spread " + format_figure(c.spread_u) + " m)";
  if (std::isfinite(c.geoid_n)) c.figures += ", EGM96 geoid undulation there " + format_figure(c.geoid_n) + " m";
  return c;
}

GcpCheck check_gcps(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                    const AdjustOptions& options, const AdjustResult& with) {
  GcpCheck c;
  AdjustOptions free_options = options;
  free_options.control.clear();
  free_options.progress = false;
  free_options.keep_untrusted = false;  // a free fit that fails too: the models or the tracks are wrong
  const AdjustResult free_fit = adjust_rpcs(images, tracks, free_options);
  double s[2] = {0, 0};
  long n = 0;
  for (size_t k = 0; k < with.obs_track.size(); ++k) {
    const size_t t = static_cast<size_t>(with.obs_track[k]);
    if (with.flagged[t] || free_fit.flagged[t]) continue;
    if ((t < with.views_dropped.size() && with.views_dropped[t]) || (t < free_fit.views_dropped.size() && free_fit.views_dropped[t])) continue;
    s[0] += with.res_after[k].squaredNorm();
    s[1] += free_fit.res_after[k].squaredNorm();
    ++n;
  }
  for (size_t t = 0; t < with.flagged.size(); ++t) c.common_tracks += with.initial_ok[t] && !with.flagged[t] && !free_fit.flagged[t];
  c.flagged_with = std::count(with.flagged.begin(), with.flagged.end(), 1);
  c.flagged_without = std::count(free_fit.flagged.begin(), free_fit.flagged.end(), 1);
  c.rms_with = n ? std::sqrt(s[0] / n) : NAN;
  c.rms_without = n ? std::sqrt(s[1] / n) : NAN;
  for (size_t p = 0; p < options.control.size(); ++p) {
    const AdjustControl& gc = options.control[p];
    const Eigen::Vector3d g = with.control_ground[p];
    const Eigen::Vector3d enu = (g - gc.llh).cwiseProduct(metres_per_degree(gc.llh[1]));
    double worst = enu.cwiseQuotient(gc.sigma_enu).cwiseAbs().maxCoeff();
    for (size_t k = 0; k < gc.views.size(); ++k) {
      const auto& [i, xy] = gc.views[k];
      const RpcObservation o{&images[i].model, &with.bias[i], xy};
      worst = std::max(worst, (rpc_observe(o, g) - xy).cwiseAbs().maxCoeff() / std::max(gc.sigma_px[k], kMinObservationSigma));
    }
    if (worst > c.worst_normalized) c.worst_normalized = worst, c.worst_id = gc.id, c.worst_enu = enu;
  }
  c.contradicts = c.rms_with > 1.2 * c.rms_without + 0.25 * with.reference_sigma_px || c.worst_normalized > 5 ||
                  c.flagged_with - c.flagged_without > std::max<long>(10, static_cast<long>(free_fit.flagged.size() / 100));
  c.figures = "rms after " + format_figure(c.rms_with) + " px with the GCPs, " + format_figure(c.rms_without) +
              " px without (over the " + std::to_string(c.common_tracks) + " tracks neither flags); largest normalized GCP residual " +
              format_figure(c.worst_normalized) + " sigma at point " + std::to_string(c.worst_id) + " (adjusted minus given: e " +
              format_figure(c.worst_enu[0], 3) + " m, n " + format_figure(c.worst_enu[1], 3) + " m, u " + format_figure(c.worst_enu[2], 3) + " m); flagged tracks " +
              std::to_string(c.flagged_with) + " with, " + std::to_string(c.flagged_without) + " without";
  return c;
}

double held_out_rms(const std::vector<AdjustImage>& images, const std::vector<ImageBias>& bias,
                    const std::vector<AdjustTrack>& tracks, long* n_out) {
  check_tracks(images, tracks);
  double s = 0;
  long n = 0;
  for (const auto& t : tracks) {
    auto v = observations(images, &bias, t);
    RpcIntersection x = intersect_rpc(v);
    if (!x.ok) continue;
    s += x.rms_px * x.rms_px * v.size();
    n += static_cast<long>(v.size());
  }
  if (n_out) *n_out = n;
  return n ? std::sqrt(s / n) : std::numeric_limits<double>::quiet_NaN();
}


GroundSolution ground_points(const std::vector<AdjustImage>& images, const std::vector<AdjustTrack>& tracks,
                             const GroundOptions& o) {
  GroundSolution g;
  g.points.resize(tracks.size());
  g.flags.assign(tracks.size(), 0);
  parallel_for(tracks.size(), o.threads, [&](size_t t) { g.points[t] = intersect_rpc(observations(images, nullptr, tracks[t])); });
  double sum = 0;
  long n = 0;
  std::vector<double> rms;
  for (size_t t = 0; t < tracks.size(); ++t) {
    const RpcIntersection& x = g.points[t];
    if (!x.ok) continue;
    ++g.intersected;
    sum += x.rms_px * x.rms_px * tracks[t].views.size();
    n += static_cast<long>(tracks[t].views.size());
    rms.push_back(x.rms_px);
    if (x.rms_px > o.flag_px) g.flags[t] |= kGroundResidual, ++g.residual_flagged;
    for (const auto& [i, xy] : tracks[t].views)
      if (images[i].model.outside_validity_box(x.llh)) {
        g.flags[t] |= kGroundOutsideBox;
        ++g.outside_box;
        break;
      }
  }
  std::string names;
  for (const auto& im : images) names += (names.empty() ? "" : ", ") + im.path;
  if (n == 0)
    throw NumericalError("no track could be intersected with the RPC models of " + names +
                         " (do the models belong to these images, and do the images overlap?)");
  g.rms_px = std::sqrt(sum / n);
  g.sigma0 = std::sqrt(sum / (2.0 * n));
  std::nth_element(rms.begin(), rms.begin() + rms.size() / 2, rms.end());
  g.median_rms_px = rms[rms.size() / 2];
  if (2 * g.residual_flagged <= g.intersected) return g;
  const std::string figures = std::to_string(g.residual_flagged) + " of " + std::to_string(g.intersected) +
                              " tracks have an RMS residual above --flag " + format_figure(o.flag_px) + " px (median " +
                              format_figure(g.median_rms_px) + " px)";
  // Biased models, or models that cannot be right? A shift per image (the first fixed) fitted to the tracks
  // tells them apart: it explains delivered models' disagreement (Grodecki & Dial 2003: a shift over a
  // scene), not another image's model (another orientation: 0.9 px left by an affine bias on a 256 px
  // tp-synth scene, which a shift does not absorb).
  AdjustOptions ao;
  ao.model = BiasModel::shift;  // delivered models' errors are shifts over a scene; another image's model is no shift
  ao.flag_px = o.flag_px;
  ao.threads = o.threads;
  ao.keep_untrusted = true;
  ao.drop_views = false;
  std::vector<AdjustImage> fixed_first = images;
  for (size_t i = 0; i < fixed_first.size(); ++i) fixed_first[i].fixed = i == 0;
  FitTrust trust;
  AdjustResult fit;
  try {
    fit = adjust_rpcs(fixed_first, tracks, ao);
    trust = fit_trust(fixed_first, tracks, fit, o.flag_px);
  } catch (const NumericalError& e) {
    trust.figures = e.what();
  }
  if (!trust.ok())
    throw NumericalError(figures + ": the RPC models of " + names + " do not fit the tracks, and no bias of the models explains them (" +
                         trust.figures + "): another image's model? offsets swapped?");
  g.bias_fit_rms_px = inlier_rms(fit);
  g.max_shift_px = 0;
  std::string beyond;
  for (size_t i = 0; i < images.size(); ++i) {
    const AdjustImage& im = images[i];
    const Eigen::Vector2d c(0.5 * (im.width - 1), 0.5 * (im.height - 1));
    const double shift = fit.bias[i].offset(c).norm();
    if (shift > g.max_shift_px) g.max_shift_px = shift, g.max_shift_image = static_cast<int>(i);
    const double limit = delivered_bias_bound_px(im);
    const double stated = std::hypot(std::max(0.0, im.model.err_bias), std::max(0.0, im.model.err_rand));
    if (shift > limit && beyond.empty())
      beyond = im.path + "'s model is " + format_figure(shift) + " px off the others' (beyond " + format_figure(limit) +
               " px: no delivered model's error" + (stated > 0 ? ", " + format_figure(kGroundStatedErrors) + " times its stated " + format_figure(stated) + " m" : std::string()) + ")";
  }
  if (!beyond.empty())
    throw NumericalError(figures + ": the RPC models of " + names + " do not fit the tracks: " + beyond +
                         " (another scene's model? offsets swapped?)");
  g.biased = true;
  g.warning = figures + ": the delivered models disagree by a bias (a shift per image, the first fixed, fits the tracks to " +
              format_figure(g.bias_fit_rms_px) + " px RMS; the largest shift " + format_figure(g.max_shift_px) + " px, " +
              images[static_cast<size_t>(g.max_shift_image)].path + "): the points are written, those tracks flagged 1; rpc-adjust removes the bias";
  return g;
}

double model_gsd(const RpcModel& m, long width, long height) {
  try {
    const double x = 0.5 * (width - 1), y = 0.5 * (height - 1), h = m.height_off;
    const Eigen::Vector2d p = m.localize(x, y, h), px = m.localize(x + 1, y, h), py = m.localize(x, y + 1, h);
    const Eigen::Vector3d mpd = metres_per_degree(p[1]);
    const double dx = std::hypot((px[0] - p[0]) * mpd[0], (px[1] - p[1]) * mpd[1]);
    const double dy = std::hypot((py[0] - p[0]) * mpd[0], (py[1] - p[1]) * mpd[1]);
    return std::sqrt(dx * dy);
  } catch (const NumericalError&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

RpcFit fold_bias(const RpcModel& m, const ImageBias& bias, long width, long height, double h_lo, double h_hi) {
  RpcFitVolume v;
  v.lon0 = v.lat0 = std::numeric_limits<double>::infinity();
  v.lon1 = v.lat1 = -v.lon0;
  v.h0 = h_lo;
  v.h1 = h_hi;
  const double xs[] = {-0.5, width - 0.5}, ys[] = {-0.5, height - 0.5};
  for (double h : {h_lo, h_hi})
    for (double x : xs)
      for (double y : ys) {
        Eigen::Vector2d ll = m.localize(x, y, h);
        v.lon0 = std::min(v.lon0, ll[0]);
        v.lon1 = std::max(v.lon1, ll[0]);
        v.lat0 = std::min(v.lat0, ll[1]);
        v.lat1 = std::max(v.lat1, ll[1]);
      }
  RpcFit f = fit_rpc([&](const Eigen::Vector3d& g) { return bias.apply(m.project(g)); }, v);
  f.model.err_bias = m.err_bias;
  f.model.err_rand = m.err_rand;
  return f;
}

}  // namespace tpkit

// ---------------------------------------------------------------- tracks, priors, figure (tool support)

namespace tpkit {

namespace {
// A sigma read from a file: NaN (not known) or >= 0; negative or infinite refused with its line.
double checked_sigma(double s, const std::string& source, long line, const std::string& column) {
  if (std::isnan(s)) return s;
  if (s < 0 || std::isinf(s))
    throw InputError(source, line, column + " " + format_number(s) + " is not a standard deviation (pixels, >= 0; nan when not known)");
  return s;
}
}  // namespace

std::vector<AdjustTrack> tracks_to_adjust(const Tracks& t, const std::vector<int>& image_of_view) {
  const int K = t.views();
  if (static_cast<int>(image_of_view.size()) != K)
    throw InputError(t.source, 0, "the header names " + std::to_string(image_of_view.size()) + " images for " + std::to_string(K) + " views");
  std::vector<int> sigma_col(K, -1);
  for (int v = 0; v < K; ++v) sigma_col[v] = t.extra.find("sigma" + std::to_string(v + 1));
  const bool any_sigma = std::any_of(sigma_col.begin(), sigma_col.end(), [](int c) { return c >= 0; });
  std::vector<AdjustTrack> out;
  out.reserve(t.size());
  for (size_t r = 0; r < t.size(); ++r) {
    AdjustTrack a;
    a.source = t.source;
    a.id = t.id[r];
    a.line = r < t.line.size() ? t.line[r] : 0;
    for (int v = 0; v < K; ++v) {
      const Eigen::Vector2d xy = t.point(r, v);
      const bool nx = std::isnan(xy[0]), ny = std::isnan(xy[1]);
      if (nx != ny)
        throw InputError(t.source, a.line, "track " + std::to_string(a.id) + ": view " + std::to_string(v + 1) + " has " +
                                               (nx ? "x" : "y") + std::to_string(v + 1) + " nan and " + (nx ? "y" : "x") +
                                               std::to_string(v + 1) + " a number: a view not seen is nan in both");
      if (nx) continue;  // not seen in this view: no observation
      a.views.emplace_back(image_of_view[v], xy);
      if (any_sigma)
        a.sigma.push_back(sigma_col[v] < 0 ? std::numeric_limits<double>::quiet_NaN()
                                           : checked_sigma(t.extra.values(r, sigma_col[v]), t.source, a.line, "sigma" + std::to_string(v + 1)));
    }
    if (a.views.size() < 2)
      throw InputError(t.source, a.line, "track " + std::to_string(a.id) + " is seen in " + std::to_string(a.views.size()) +
                                             " view" + (a.views.size() == 1 ? "" : "s") + ": a track needs two or more");
    out.push_back(std::move(a));
  }
  return out;
}

std::vector<AdjustTrack> matches_to_adjust(const Matches& m, int image1, int image2) {
  const int sc = m.extra.find("sigma");
  std::vector<AdjustTrack> out;
  out.reserve(m.size());
  for (size_t r = 0; r < m.size(); ++r) {
    AdjustTrack a;
    a.source = m.source;
    a.id = static_cast<long long>(r) + 1;
    a.line = r < m.line.size() ? m.line[r] : 0;
    const Eigen::Vector2d p1 = m.xy.block<1, 2>(r, 0).transpose(), p2 = m.xy.block<1, 2>(r, 2).transpose();
    if (!p1.allFinite() || !p2.allFinite())
      throw InputError(m.source, a.line, "match " + std::to_string(a.id) + ": a position that is not a number");
    a.views = {{image1, p1}, {image2, p2}};
    if (sc >= 0) {
      // the sigma of (x2, y2) relative to (x1, y1): each view's own is sigma / sqrt(2)
      const double s = checked_sigma(m.extra.values(r, sc), m.source, a.line, "sigma") / std::sqrt(2.0);
      a.sigma = {s, s};
    }
    out.push_back(std::move(a));
  }
  return out;
}

std::vector<AdjustTrack> gather_tracks(const std::vector<std::string>& files, const std::vector<std::string>& images) {
  std::vector<AdjustTrack> out;
  auto image_of = [&](const std::string& f, const std::string& source, const std::vector<ImageRef>& refs) {
    std::vector<int> map;
    for (size_t k = 0; k < refs.size(); ++k) {
      int i = image_index(refs[k].path, images, f);
      if (i < 0)
        throw InputError(source, 0, "image" + std::to_string(k + 1) + " '" + refs[k].path + "' is " +
                                        (i == -2 ? "ambiguous among" : "not one of") + " the images given");
      for (size_t j = 0; j < map.size(); ++j)
        if (map[j] == i)
          throw InputError(source, 0, "image" + std::to_string(j + 1) + " and image" + std::to_string(k + 1) + " are both " +
                                          images[i] + ": a track views each image once");
      map.push_back(i);
    }
    return map;
  };
  for (const auto& f : files) {
    // the kind from the header, the input read once (a pipe cannot be read twice)
    TextInput input(f);
    const std::string kind = input.header_kind();
    const bool is_matches = kind == "matches";
    if (!kind.empty() && kind != "matches" && kind != "tracks")
      throw InputError(f == "-" ? "<stdin>" : f, 1, "a " + kind + " file: tie points are a tracks or a matches file");
    auto table = [&](const ReadOptions& opt) { return read_table(input.stream(), f, opt); };
    std::vector<AdjustTrack> part;
    if (is_matches) {
      Matches m = matches_from_table(table(matches_read_options()));
      if (m.image1.path.empty() || m.image2.path.empty())
        throw InputError(m.source, 0, "a matches file needs its image1 and image2 header lines to be matched to the images");
      std::vector<int> map = image_of(f, m.source, {m.image1, m.image2});
      part = matches_to_adjust(m, map[0], map[1]);
    } else {
      Tracks t = tracks_from_table(table(tracks_read_options()));
      std::vector<int> map = image_of(f, t.source, t.images);
      if (static_cast<int>(map.size()) != t.views())
        throw InputError(t.source, 0, "the header names " + std::to_string(map.size()) + " images for " +
                                          std::to_string(t.views()) + " views");
      part = tracks_to_adjust(t, map);
    }
    out.insert(out.end(), std::make_move_iterator(part.begin()), std::make_move_iterator(part.end()));
  }
  return out;
}

HeightPrior parse_height_prior(const std::string& text) {
  std::string h = text, s;
  for (const char* sep : {"\xC2\xB1", "+-", ","}) {
    size_t k = text.find(sep);
    if (k != std::string::npos) {
      h = text.substr(0, k);
      s = text.substr(k + std::strlen(sep));
      break;
    }
  }
  double hv, sv;
  size_t u1 = 0, u2 = 0;
  try {
    hv = std::stod(h, &u1);
    sv = std::stod(s, &u2);
  } catch (...) {
    u1 = 0;
  }
  if (u1 == 0 || u1 != h.size() || u2 != s.size() || !std::isfinite(hv) || !(sv > 0) || !std::isfinite(sv))
    throw UsageError("--height-prior: expected H+-S (metres above the ellipsoid, S > 0), got '" + text + "'");
  if (sv < kMinHeightSigma)
    throw UsageError("--height-prior: S = " + format_number(sv) + " m is below " + format_number(kMinHeightSigma) +
                     " m (no height is known that well; the adjustment's cost would overflow)");
  HeightPrior p;
  p.sigma = sv;
  p.at = [hv](double, double, double& out, double* grad) {
    out = hv;
    if (grad) grad[0] = grad[1] = 0;
    return true;
  };
  return p;
}

GeoBounds model_bounds(const RpcModel& m) {
  return {m.lon_off - std::fabs(m.lon_scale), m.lon_off + std::fabs(m.lon_scale), m.lat_off - std::fabs(m.lat_scale),
          m.lat_off + std::fabs(m.lat_scale)};
}

GeoBounds models_bounds(const std::vector<AdjustImage>& images) {
  GeoBounds b{INFINITY, -INFINITY, INFINITY, -INFINITY};
  for (const auto& im : images) {
    const GeoBounds m = model_bounds(im.model);
    b.lon0 = std::min(b.lon0, m.lon0), b.lon1 = std::max(b.lon1, m.lon1);
    b.lat0 = std::min(b.lat0, m.lat0), b.lat1 = std::max(b.lat1, m.lat1);
  }
  return b;
}

HeightPrior dem_height_prior(const GeoGrid& dem, double sigma) {
  auto grid = std::make_shared<GeoGrid>(dem);
  HeightPrior p;
  p.sigma = sigma;
  p.at = [grid](double lon, double lat, double& h, double* grad) {
    const GeoGrid& g = *grid;
    double fx = (lon - g.lon0) / g.dlon, fy = (g.lat0 - lat) / g.dlat;
    if (!(fx >= 0) || !(fy >= 0) || fx > g.width - 1 || fy > g.height - 1) return false;
    long x0 = std::min(static_cast<long>(fx), g.width - 2), y0 = std::min(static_cast<long>(fy), g.height - 2);
    if (g.width < 2 || g.height < 2) return false;
    double ax = fx - x0, ay = fy - y0;
    auto at = [&](long x, long y) { return static_cast<double>(g.data[static_cast<size_t>(y) * g.width + x]); };
    const double z00 = at(x0, y0), z10 = at(x0 + 1, y0), z01 = at(x0, y0 + 1), z11 = at(x0 + 1, y0 + 1);
    h = (1 - ay) * ((1 - ax) * z00 + ax * z10) + ay * ((1 - ax) * z01 + ax * z11);
    if (grad) {
      grad[0] = ((1 - ay) * (z10 - z00) + ay * (z11 - z01)) / g.dlon;
      grad[1] = -((1 - ax) * (z01 - z00) + ax * (z11 - z10)) / g.dlat;  // rows run south
    }
    return std::isfinite(h);
  };
  return p;
}

}  // namespace tpkit
