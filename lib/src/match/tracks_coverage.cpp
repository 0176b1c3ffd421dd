#include "tpkit/match/tracks_coverage.hpp"

#include <cmath>
#include <filesystem>

#include "tpkit/core/coverage_plot.hpp"

namespace tpkit {

void save_tracks_coverage(const std::string& path, const TrackChainer& chainer) {
  const Tracks h = chainer.header();
  std::vector<CoverageView> views(h.images.size());
  for (size_t k = 0; k < views.size(); ++k) {
    views[k].title = std::filesystem::path(h.images[k].path).filename().string();
    views[k].image = h.images[k].path;
    views[k].width = static_cast<double>(h.images[k].width);
    views[k].height = static_cast<double>(h.images[k].height);
  }
  chainer.for_each([&](long long, const double* xy, const double*) {
    for (size_t k = 0; k < views.size(); ++k)
      if (std::isfinite(xy[2 * k])) views[k].x.push_back(xy[2 * k]), views[k].y.push_back(xy[2 * k + 1]);
  });
  coverage_figure(views, "tie points per cell (tracks), over each image").save(path);
}

void save_matches_coverage(const std::string& path, const Matches& m) {
  std::vector<CoverageView> views(2);
  const ImageRef* refs[2] = {&m.image1, &m.image2};
  for (int k = 0; k < 2; ++k) {
    views[k].title = std::filesystem::path(refs[k]->path).filename().string();
    views[k].image = refs[k]->path;
    views[k].width = static_cast<double>(refs[k]->width);
    views[k].height = static_cast<double>(refs[k]->height);
    for (size_t i = 0; i < m.size(); ++i) {
      views[k].x.push_back(m.xy(static_cast<Eigen::Index>(i), 2 * k));
      views[k].y.push_back(m.xy(static_cast<Eigen::Index>(i), 2 * k + 1));
    }
  }
  coverage_figure(views, "tie points per cell (matches), over each image").save(path);
}

}  // namespace tpkit
