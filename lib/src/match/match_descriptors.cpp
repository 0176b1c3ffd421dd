#include "tpkit/match/match_descriptors.hpp"

#include <algorithm>
#include <numeric>
#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>

namespace tpkit {

namespace {
// For each row of q, its two nearest neighbours in t (distances as L2, not squared).
void knn2(const cv::Mat& q, const cv::Mat& t, bool exact, const DescriptorMatchOptions& o, std::vector<std::vector<cv::DMatch>>& out) {
  out.clear();
  if (q.rows == 0 || t.rows == 0) {
    out.resize(q.rows);
    return;
  }
  if (exact) {
    cv::BFMatcher bf(cv::NORM_L2);
    bf.knnMatch(q, t, out, 2);
  } else {
    cv::flann::KDTreeIndexParams ip(o.flann_trees);
    cv::flann::SearchParams sp(o.flann_checks);
    cv::flann::Index index(t, ip, cvflann::FLANN_DIST_L2);
    cv::Mat idx(q.rows, 2, CV_32S), dist(q.rows, 2, CV_32F);
    index.knnSearch(q, idx, dist, std::min(2, t.rows), sp);
    out.resize(q.rows);
    for (int r = 0; r < q.rows; ++r) {
      for (int k = 0; k < std::min(2, t.rows); ++k) {
        int j = idx.at<int>(r, k);
        if (j < 0 || j >= t.rows) continue;
        out[r].emplace_back(r, j, std::sqrt(std::max(0.f, dist.at<float>(r, k))));
      }
    }
  }
}
}  // namespace

std::vector<DescriptorMatch> match_descriptors(const cv::Mat& d1in, const cv::Mat& d2in, const DescriptorMatchOptions& o) {
  std::vector<DescriptorMatch> res;
  if (d1in.rows == 0 || d2in.rows == 0) return res;
  cv::Mat desc1, desc2;  // FLANN's kd-trees need float
  d1in.convertTo(desc1, CV_32F);
  d2in.convertTo(desc2, CV_32F);
  // FLANN's kd-tree randomness comes from the C library rand(): fix it for determinism
  bool exact = desc1.rows < o.exact_below && desc2.rows < o.exact_below;
  std::vector<std::vector<cv::DMatch>> f, b;
  cv::theRNG().state = 0x1234567;
  std::srand(12345);
  knn2(desc1, desc2, exact, o, f);
  // ratio test first; the mutual check then only queries the image-2 descriptors that won
  std::vector<DescriptorMatch> cand;
  for (int i = 0; i < desc1.rows; ++i) {
    if (f[i].empty()) continue;
    const cv::DMatch& m = f[i][0];
    float ratio = 0.f;
    if (f[i].size() > 1) {
      float d2 = f[i][1].distance;
      ratio = d2 > 0 ? m.distance / d2 : 1.f;
      if (ratio >= o.ratio) continue;
    } else if (desc2.rows > 1) {
      continue;  // the second neighbour is unknown: cannot test the ratio
    }
    cand.push_back({i, m.trainIdx, m.distance, ratio});
  }
  if (!o.mutual) return cand;
  std::vector<int> winners;
  for (const auto& c : cand) winners.push_back(c.i2);
  std::sort(winners.begin(), winners.end());
  winners.erase(std::unique(winners.begin(), winners.end()), winners.end());
  cv::Mat q(static_cast<int>(winners.size()), desc2.cols, desc2.type());
  for (size_t k = 0; k < winners.size(); ++k) desc2.row(winners[k]).copyTo(q.row(static_cast<int>(k)));
  std::srand(54321);
  knn2(q, desc1, exact, o, b);
  for (const auto& c : cand) {
    size_t k = static_cast<size_t>(std::lower_bound(winners.begin(), winners.end(), c.i2) - winners.begin());
    if (!b[k].empty() && b[k][0].trainIdx == c.i1) res.push_back(c);
  }
  return res;
}

std::vector<size_t> grid_select(const std::vector<cv::Point2f>& pts, const std::vector<float>& score, long width, long height,
                                int cells, int per_cell) {
  std::vector<size_t> order(pts.size());
  std::iota(order.begin(), order.end(), 0);
  if (cells <= 0 || per_cell <= 0) return order;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return score[a] < score[b]; });
  std::vector<int> count(static_cast<size_t>(cells) * cells, 0);
  std::vector<size_t> keep;
  for (size_t i : order) {
    long cx = std::clamp<long>(static_cast<long>((pts[i].x + 0.5) * cells / std::max(1L, width)), 0, cells - 1);
    long cy = std::clamp<long>(static_cast<long>((pts[i].y + 0.5) * cells / std::max(1L, height)), 0, cells - 1);
    int& c = count[static_cast<size_t>(cy * cells + cx)];
    if (c >= per_cell) continue;
    ++c;
    keep.push_back(i);
  }
  std::sort(keep.begin(), keep.end());
  return keep;
}

}  // namespace tpkit
