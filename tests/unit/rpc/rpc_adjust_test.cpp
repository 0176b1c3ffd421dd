// rpc-adjust on tracks of any length, matches files and sigma weights (issue 24). Models: the real
// Pléiades crops' tag 50844 (image 1 fixed); truth: ground points on a grid over image 1 at the heights of
// a smooth terrain h(lon, lat), projected through each model and moved by a known bias per image
// (observed = bias(rpc(g)), pixels x column, y row). The terrain is the height prior (as a DEM would be),
// which fixes the datum that tie points alone cannot see.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "pleiades_models.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {
fs::path scratch(const std::string& name) { return tpkit_test::scratch("rpc-adjust-test", name); }
std::vector<AdjustImage> pleiades() {
  auto out = tpkit_test::pleiades_images();
  out[0].fixed = true;
  return out;
}

HeightPrior terrain_prior(const RpcModel& m, double sigma) {
  HeightPrior p;
  p.sigma = sigma;
  p.at = [m](double lon, double lat, double& h, double* grad) {
    h = tpkit_test::smooth_terrain(m, lon, lat);
    if (grad) {
      const double e = 1e-7;
      grad[0] = (tpkit_test::smooth_terrain(m, lon + e, lat) - tpkit_test::smooth_terrain(m, lon - e, lat)) / (2 * e);
      grad[1] = (tpkit_test::smooth_terrain(m, lon, lat + e) - tpkit_test::smooth_terrain(m, lon, lat - e)) / (2 * e);
    }
    return true;
  };
  return p;
}

using Truth = tpkit_test::BiasedTruth;

// n x n ground points over image 1, each on all three images.
Truth truth(int n = 20) {
  Truth T;
  T.images = pleiades();
  T.bias.resize(3);
  T.bias[1].a = {3.0, 0.0004, -0.0002};
  T.bias[1].b = {-2.0, 0.0001, 0.0003};
  T.bias[2].a = {-4.0, -0.0003, 0.0001};
  T.bias[2].b = {1.5, 0.0002, -0.0004};
  tpkit_test::add_grid_points(T, n, 60, 60);
  return T;
}

// RMS over the truth points of |adjusted bias(rpc(g)) - truth pixel| in image i (px).
double truth_rms(const Truth& T, const AdjustResult& r, int i) {
  double s = 0;
  for (size_t p = 0; p < T.ground.size(); ++p)
    s += (r.bias[i].apply(T.images[i].model.project(T.ground[p])) - T.xy[p][i]).squaredNorm();
  return std::sqrt(s / T.ground.size());
}

AdjustOptions options(const Truth& T, double height_sigma = 1.0) {
  AdjustOptions o;
  o.model = BiasModel::affine;
  o.height = terrain_prior(T.images[0].model, height_sigma);
  return o;
}

// Which images point p is seen in: 3 views, or 2 of them (every pair), the missing one "nan nan".
std::vector<int> subset(size_t p) {
  switch (p % 5) {
    case 0:
    case 1: return {0, 1, 2};
    case 2: return {0, 1};
    case 3: return {0, 2};
    default: return {1, 2};
  }
}

using tpkit_test::message;
}  // namespace

// A tracks file of three images where 3 points in 5 miss a view (nan nan): the missing views are not
// observations, the tracks are 2- and 3-view, and the adjusted models reach the truth.
TEST(RpcAdjust, TracksWithMissingViewsReachTheTruth) {
  const Truth T = truth();
  Tracks tr;
  tr.source = "mixed.tracks";
  tr.xy.resize(static_cast<Eigen::Index>(T.ground.size()), 6);
  tr.xy.setConstant(std::numeric_limits<double>::quiet_NaN());
  std::map<int, long> lengths;
  std::array<std::map<int, long>, 3> per_image;
  for (size_t p = 0; p < T.ground.size(); ++p) {
    tr.id.push_back(static_cast<long long>(p) + 1);
    tr.line.push_back(static_cast<long>(p) + 5);
    const auto views = subset(p);
    for (int i : views) tr.xy.block<1, 2>(static_cast<Eigen::Index>(p), 2 * i) = T.xy[p][i].transpose();
    ++lengths[static_cast<int>(views.size())];
    for (int i : views) ++per_image[i][static_cast<int>(views.size())];
  }
  const auto tracks = tracks_to_adjust(tr, {0, 1, 2});
  ASSERT_EQ(tracks.size(), T.ground.size());
  for (size_t p = 0; p < tracks.size(); ++p) {
    ASSERT_EQ(tracks[p].views.size(), subset(p).size());
    for (const auto& [i, xy] : tracks[p].views) EXPECT_TRUE(xy.allFinite());
    EXPECT_TRUE(tracks[p].sigma.empty());  // no sigma columns: unit weights
  }
  const AdjustResult r = adjust_rpcs(T.images, tracks, options(T));
  EXPECT_EQ(tracks_by_length(tracks, r), lengths);
  EXPECT_EQ(format_lengths(lengths), "2:" + std::to_string(lengths[2]) + " 3:" + std::to_string(lengths[3]));
  const auto rep = image_reports(3, tracks, r);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(rep[i].tracks_by_length, per_image[i]) << "image " << i + 1;
    long obs = 0;
    for (const auto& [len, n] : per_image[i]) obs += n;
    EXPECT_EQ(rep[i].observations, obs);
    EXPECT_GT(rep[i].rms_before, 0.5) << "image " << i + 1;  // the biases are several pixels
    EXPECT_LT(rep[i].rms_after, 0.005) << "image " << i + 1;
    EXPECT_LT(truth_rms(T, r, i), 0.01) << "image " << i + 1;
    EXPECT_EQ(rep[i].median_sigma, 1.0);  // the default without sigmas
  }
  EXPECT_EQ(r.obs_with_sigma, 0);
}

// The matches of each pair given as files (image paths in the header, a sigma column), beside a tracks
// file: each record is a 2-view track of its two images, sigma / sqrt(2) on each view, and the block
// adjusts to the truth.
TEST(RpcAdjust, MatchesFilesAreTwoViewTracks) {
  const Truth T = truth(16);
  const std::vector<std::string> paths = {T.images[0].path, T.images[1].path, T.images[2].path};
  auto name = [](int i) { return "img_0" + std::to_string(i + 1) + ".tif"; };  // matched by file name
  std::vector<std::string> files;
  long pairs = 0, triples = 0;
  for (auto [i, j] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}}) {
    fs::path f = scratch("pair-" + std::to_string(i + 1) + "-" + std::to_string(j + 1) + ".matches");
    std::ofstream os(f);
    os << "# tpkit matches 1\n# image1: " << name(i) << "\n# image2: " << name(j) << "\n# columns: id1 x1 y1 id2 x2 y2 sigma\n";
    for (size_t p = 0; p < T.ground.size(); p += 3) {
      os << p << ' ' << format_number(T.xy[p][i][0]) << ' ' << format_number(T.xy[p][i][1]) << ' ' << p << ' '
         << format_number(T.xy[p][j][0]) << ' ' << format_number(T.xy[p][j][1]) << " 0.0707\n";
      ++pairs;
    }
    files.push_back(f.string());
  }
  {
    fs::path f = scratch("triplet.tracks");
    std::ofstream os(f);
    os << "# tpkit tracks 1\n# image1: " << name(0) << "\n# image2: " << name(1) << "\n# image3: " << name(2)
       << "\n# columns: track x1 y1 x2 y2 x3 y3\n";
    for (size_t p = 1; p < T.ground.size(); p += 3) {
      os << p;
      for (int i = 0; i < 3; ++i) os << ' ' << format_number(T.xy[p][i][0]) << ' ' << format_number(T.xy[p][i][1]);
      os << '\n';
      ++triples;
    }
    files.push_back(f.string());
  }
  const auto tracks = gather_tracks(files, paths);
  ASSERT_EQ(static_cast<long>(tracks.size()), pairs + triples);
  // the first file's first record: a track of images 1 and 2, line 5, id 1 (record number), sigma split
  EXPECT_EQ(tracks[0].views.size(), 2u);
  EXPECT_EQ(tracks[0].views[0].first, 0);
  EXPECT_EQ(tracks[0].views[1].first, 1);
  EXPECT_EQ(tracks[0].line, 5);
  EXPECT_EQ(tracks[0].id, 1);
  ASSERT_EQ(tracks[0].sigma.size(), 2u);
  EXPECT_NEAR(tracks[0].sigma[0], 0.0707 / std::sqrt(2.0), 1e-12);
  EXPECT_EQ(tracks.back().views.size(), 3u);
  EXPECT_TRUE(tracks.back().sigma.empty());
  AdjustOptions o = options(T);
  const AdjustResult r = adjust_rpcs(T.images, tracks, o);
  EXPECT_EQ(tracks_by_length(tracks, r), (std::map<int, long>{{2, pairs}, {3, triples}}));
  EXPECT_EQ(r.obs_with_sigma, 2 * pairs);
  EXPECT_NEAR(r.default_sigma_px, 0.0707 / std::sqrt(2.0), 1e-12);  // the tracks' views: the median given
  for (int i = 0; i < 3; ++i) EXPECT_LT(truth_rms(T, r, i), 0.01) << "image " << i + 1;
}

// One view much noisier than the others (1 px against 0.05 px), its sigma saying so: weighted, the other
// views fit their points better and the adjusted models come nearer the truth than unweighted.
TEST(RpcAdjust, SigmaWeightsLowerANoisyView) {
  const Truth T = truth(24);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> unit(0, 1);
  const double sigma[3] = {0.05, 0.05, 1.0};
  std::vector<AdjustTrack> tracks;
  std::vector<std::array<Eigen::Vector2d, 3>> observed;
  for (size_t p = 0; p < T.ground.size(); ++p) {
    AdjustTrack t;
    t.source = "noisy";
    t.id = static_cast<long long>(p);
    for (int i = 0; i < 3; ++i) {
      t.views.emplace_back(i, T.xy[p][i] + sigma[i] * Eigen::Vector2d(unit(rng), unit(rng)));
      t.sigma.push_back(sigma[i]);
    }
    tracks.push_back(t);
  }
  // a loose height prior (20 m): the heights come from the views, so a noisy view moves them
  AdjustOptions weighted = options(T, 20), unweighted = options(T, 20);
  unweighted.use_sigma = false;
  const AdjustResult rw = adjust_rpcs(T.images, tracks, weighted);
  const AdjustResult ru = adjust_rpcs(T.images, tracks, unweighted);
  EXPECT_EQ(rw.obs_with_sigma, static_cast<long>(3 * tracks.size()));
  EXPECT_EQ(ru.obs_with_sigma, 0);
  for (int i = 0; i < 2; ++i) {
    const double w = residual_rms(rw, true, i), u = residual_rms(ru, true, i);
    EXPECT_LT(w, 0.5 * u) << "image " << i + 1 << ": residual rms weighted " << w << " px, unweighted " << u << " px";
    EXPECT_LT(w, 0.08) << "image " << i + 1;  // about its own noise (0.05 px per coordinate, two views in three)
  }
  // image 2's adjusted model: nearer the truth weighted; image 3's residuals take the noise
  const double tw = truth_rms(T, rw, 1), tu = truth_rms(T, ru, 1);
  EXPECT_LT(tw, 0.5 * tu) << "image 2 against the truth: weighted " << tw << " px, unweighted " << tu << " px";
  EXPECT_GT(residual_rms(rw, true, 2), residual_rms(ru, true, 2));
  // the sigmas are right: the weighted residuals' RMS per coordinate is s_ref (the median sigma, 0.05 px)
  // times sqrt(redundancy / observations), (6 - 3) / 6 per track: 0.035 px
  EXPECT_EQ(rw.reference_sigma_px, 0.05);
  EXPECT_GT(rw.sigma0_weighted, 0.65 * 0.05);
  EXPECT_LT(rw.sigma0_weighted, 0.77 * 0.05);
  // one sigma for all (LSM's 0.02 px): the unweighted fit, not a fit whose priors weigh 2500 times less
  // (which drifts along the height plane the tie points cannot see)
  std::vector<AdjustTrack> equal = tracks;
  for (auto& t : equal) t.sigma = {0.02, 0.02, 0.02};
  const AdjustResult re = adjust_rpcs(T.images, equal, weighted);
  for (int i = 1; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(re.bias[i].a[k], ru.bias[i].a[k], 1e-6 * (k ? 1e-3 : 1)) << "image " << i + 1 << " a" << k;
      EXPECT_NEAR(re.bias[i].b[k], ru.bias[i].b[k], 1e-6 * (k ? 1e-3 : 1)) << "image " << i + 1 << " b" << k;
    }
  // the floor: a sigma of 0 weighs as kMinObservationSigma, not infinitely
  std::vector<AdjustTrack> zero = tracks;
  for (auto& t : zero) t.sigma = {0.0, 0.0, 1.0};
  const AdjustResult rz = adjust_rpcs(T.images, zero, weighted);
  for (size_t k = 0; k < rz.obs_sigma.size(); ++k)
    EXPECT_EQ(rz.obs_sigma[k], rz.obs_image[k] == 2 ? 1.0 : kMinObservationSigma);
  EXPECT_TRUE(std::isfinite(residual_rms(rz, true)));
}

// What is refused, with the file and line: a track seen in one view, nan in x but not y, a negative sigma;
// and a NaN coordinate never reaches the adjustment.
TEST(RpcAdjust, RefusesOneViewTracksAndHalfMissingViews) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Tracks tr;
  tr.source = "t.tracks";
  tr.id = {7};
  tr.line = {12};
  tr.xy.resize(1, 6);
  tr.xy << 10, 20, nan, nan, nan, nan;
  EXPECT_EQ(message([&] { tracks_to_adjust(tr, {0, 1, 2}); }), "t.tracks:12: track 7 is seen in 1 view: a track needs two or more");
  tr.xy << 10, 20, nan, 30, 40, 50;
  EXPECT_EQ(message([&] { tracks_to_adjust(tr, {0, 1, 2}); }),
            "t.tracks:12: track 7: view 2 has x2 nan and y2 a number: a view not seen is nan in both");
  tr.xy << 10, 20, nan, nan, 40, 50;
  tr.extra.names = {"sigma1", "sigma2", "sigma3"};
  tr.extra.values.resize(1, 3);
  tr.extra.values << 0.1, nan, -0.2;
  EXPECT_EQ(message([&] { tracks_to_adjust(tr, {0, 1, 2}); }),
            "t.tracks:12: sigma3 -0.2 is not a standard deviation (pixels, >= 0; nan when not known)");
  tr.extra.values << 0.1, nan, 0.3;
  auto ok = tracks_to_adjust(tr, {0, 1, 2});
  ASSERT_EQ(ok.size(), 1u);
  ASSERT_EQ(ok[0].views.size(), 2u);
  EXPECT_EQ(ok[0].views[1].first, 2);
  EXPECT_EQ(ok[0].sigma, (std::vector<double>{0.1, 0.3}));
  // a track built in memory with a NaN position is refused before any arithmetic
  const auto images = pleiades();
  AdjustTrack t;
  t.source = "mem";
  t.line = 3;
  t.id = 1;
  t.views = {{0, {100, 100}}, {1, {nan, nan}}};
  EXPECT_EQ(message([&] { check_tracks(images, {t}); }), "mem:3: track 1: view 2 at (nan, nan) is not a position (a view not seen is left out)");
  t.views[1].second = {100, 100};
  t.sigma = {0.1};
  EXPECT_EQ(message([&] { check_tracks(images, {t}); }), "mem:3: track 1 has 1 sigmas for 2 views");
  // a matches record with a negative sigma
  Matches m;
  m.source = "p.matches";
  m.xy.resize(1, 4);
  m.xy << 1, 2, 3, 4;
  m.line = {9};
  m.extra.names = {"sigma"};
  m.extra.values.resize(1, 1);
  m.extra.values << -1;
  EXPECT_EQ(message([&] { matches_to_adjust(m, 0, 1); }), "p.matches:9: sigma -1 is not a standard deviation (pixels, >= 0; nan when not known)");
}
