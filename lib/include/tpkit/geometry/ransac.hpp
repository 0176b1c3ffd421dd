// A generic robust estimator: MSAC scoring with local optimization (LO-RANSAC), after PoseLib's
// ransac<Estimator> and OpenMVG's kernels.
//
// The Estimator interface (all const; the estimator holds the data):
//   using Model = ...;                        // what is estimated
//   size_t size() const;                      // number of data (tracks, matches, ...)
//   int sample_size() const;                  // size of a minimal sample
//   void generate(const std::vector<size_t>& sample, std::vector<Model>& models) const;
//                                             // 0, 1 or more models from a minimal sample (append)
//   double error2(const Model& m, size_t i) const;
//                                             // squared error of datum i, in the unit of threshold^2
//   bool refine(const std::vector<size_t>& inliers, Model& m) const;
//                                             // least-squares re-fit on an inlier set (LO step, final
//                                             // fit); false when it cannot (m is left unchanged)
// Score (MSAC): sum_i min(error2, threshold^2), lower is better. Whenever a sample gives a new best
// model, LO re-fits it on its inliers (error2 <= threshold^2) up to `lo_steps` times while the score
// improves. The number of samples adapts to the best inlier ratio w: N = log(1 - confidence) /
// log(1 - w^s), between min_iterations and max_iterations. Samples are drawn with std::mt19937_64 seeded
// by `seed`: the same data and seed give the same result.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace tpkit {

struct RansacOptions {
  double threshold = 1.5;  // in the unit of the estimator's error (pixels for the geometry estimators)
  std::uint64_t seed = 1;
  int min_iterations = 10;
  int max_iterations = 10000;
  double confidence = 0.9999;
  int lo_steps = 4;
};

template <class Model>
struct RansacResult {
  Model model{};
  bool found = false;
  std::vector<char> inlier;  // per datum
  size_t inliers = 0;
  int iterations = 0;
  double score = std::numeric_limits<double>::infinity();
};

template <class Estimator>
RansacResult<typename Estimator::Model> ransac(const Estimator& est, const RansacOptions& opt) {
  using Model = typename Estimator::Model;
  RansacResult<Model> best;
  const size_t n = est.size();
  const int s = est.sample_size();
  if (n < static_cast<size_t>(s) || s <= 0) return best;
  const double th2 = opt.threshold * opt.threshold;
  auto score = [&](const Model& m, std::vector<size_t>* inl) {
    double sc = 0;
    if (inl) inl->clear();
    for (size_t i = 0; i < n; ++i) {
      const double e = est.error2(m, i);
      if (e <= th2) {
        sc += e;
        if (inl) inl->push_back(i);
      } else {
        sc += th2;
      }
    }
    return sc;
  };
  std::mt19937_64 rng(opt.seed);
  std::uniform_int_distribution<size_t> pick(0, n - 1);
  std::vector<size_t> sample(s), inl, best_inl;
  std::vector<Model> models;
  long needed = opt.max_iterations;
  int it = 0;
  for (; it < opt.max_iterations && (it < opt.min_iterations || it < needed); ++it) {
    for (int k = 0; k < s; ++k) {
      size_t c;
      do c = pick(rng);
      while (std::find(sample.begin(), sample.begin() + k, c) != sample.begin() + k);
      sample[k] = c;
    }
    models.clear();
    est.generate(sample, models);
    for (Model& m : models) {
      double sc = score(m, &inl);
      if (sc >= best.score) continue;
      // local optimization: re-fit on the inliers while it helps
      for (int lo = 0; lo < opt.lo_steps && inl.size() >= static_cast<size_t>(s); ++lo) {
        Model r = m;
        if (!est.refine(inl, r)) break;
        std::vector<size_t> rinl;
        double rs = score(r, &rinl);
        if (rs >= sc) break;
        m = r;
        sc = rs;
        inl.swap(rinl);
      }
      best.model = m;
      best.score = sc;
      best.found = true;
      best_inl = inl;
      const double w = static_cast<double>(inl.size()) / n;
      const double pw = std::pow(w, s);
      if (pw >= 1.0) needed = 0;
      else if (pw > 0) needed = static_cast<long>(std::ceil(std::log(1 - opt.confidence) / std::log(1 - pw)));
    }
  }
  best.iterations = it;
  best.inlier.assign(n, 0);
  for (size_t i : best_inl) best.inlier[i] = 1;
  best.inliers = best_inl.size();
  return best;
}

}  // namespace tpkit
