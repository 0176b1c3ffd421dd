#include "tpkit/match/relative_blur.hpp"

#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>

namespace tpkit {

void blur_raster(Raster& r, double sigma) {
  if (!(sigma > 0) || r.data.empty()) return;
  const int W = static_cast<int>(r.width), H = static_cast<int>(r.height);
  cv::Mat v(H, W, CV_32F, r.data.data());
  cv::Mat w(H, W, CV_32F), vw(H, W, CV_32F);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const float a = v.at<float>(y, x);
      const bool ok = !std::isnan(a);
      w.at<float>(y, x) = ok ? 1.f : 0.f;
      vw.at<float>(y, x) = ok ? a : 0.f;
    }
  cv::GaussianBlur(vw, vw, cv::Size(0, 0), sigma, sigma, cv::BORDER_CONSTANT);
  cv::GaussianBlur(w, w, cv::Size(0, 0), sigma, sigma, cv::BORDER_CONSTANT);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      float& a = v.at<float>(y, x);
      if (std::isnan(a)) continue;
      a = vw.at<float>(y, x) / w.at<float>(y, x);  // w > 0: the pixel itself has weight
    }
}

RelativeBlur estimate_relative_blur(const std::function<double(double)>& score, double max_sigma, double step, double min_gain) {
  std::map<double, double> seen;
  RelativeBlur out;
  auto at = [&](double s) {
    auto it = seen.find(s);
    if (it != seen.end()) return it->second;
    ++out.evaluations;
    return seen[s] = score(s);
  };
  const double none = at(0);
  double best = 0, best_score = none;
  for (double dir : {1.0, -1.0}) {
    double s = dir * step;
    while (std::abs(s) <= max_sigma + 1e-9) {
      const double v = at(s);
      if (!(v > best_score)) break;
      best = s, best_score = v;
      s += dir * step;
    }
    if (best != 0) break;  // improved on this side: the other side is not searched
  }
  if (best != 0)
    for (double s : {best - step / 2, best + step / 2}) {
      if (std::abs(s) > max_sigma + 1e-9) continue;
      const double v = at(s);
      if (v > best_score) best = s, best_score = v;
    }
  out.score_none = none;
  if (best_score > none + min_gain) {
    out.sigma = best;
    out.score = best_score;
  } else {
    out.score = none;
  }
  return out;
}

}  // namespace tpkit
