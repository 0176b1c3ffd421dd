// tp-synth blocks (--views N, --dates D): the truth tracks of a 12-view block are the projections of their
// ground points through each view that sees them (NaN elsewhere, 2 views or more), neighbouring footprints
// overlap 30-70%, the tri-stereo default is untouched, 24 views work, the RPC of every view fits its
// camera, random biases stay within their bound, and an RPC adjustment of the block with biases of 10 px on
// 11 views recovers the truth.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>

#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_ground.hpp"
#include "tpkit/synth/synth_rpc.hpp"
#include "tpkit/synth/synth_scene.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {

SynthParams block_params(int views, int dates, uint64_t seed = 5) {
  SynthParams p;
  p.seed = seed;
  p.size = 256;
  p.relief = 40;
  p.gsd = 0.5;
  p.points = 400;
  p.supersample = 1;
  p.views = views;
  p.dates = dates;
  return p;
}

// Every truth track: >= 2 views; a seen view's position is the projection of the ground point to 1e-6 px and
// the view sees the point; an unseen view has NaN NaN and does not see it.
void check_truth(const SynthScene& s, const SynthTruth& t) {
  const int N = s.views();
  ASSERT_EQ(t.xy.cols(), 2 * N);
  for (Eigen::Index i = 0; i < t.xy.rows(); ++i) {
    const Eigen::Vector3d P = t.ground.row(i).transpose();
    EXPECT_NEAR(P.z(), s.height(P.x(), P.y()), 1e-9);
    int seen = 0;
    for (int v = 0; v < N; ++v) {
      const bool nan_x = std::isnan(t.xy(i, 2 * v)), nan_y = std::isnan(t.xy(i, 2 * v + 1));
      ASSERT_EQ(nan_x, nan_y) << "track " << i << " view " << v;
      if (nan_x) {
        EXPECT_FALSE(s.visible(v, P)) << "track " << i << " view " << v << " sees the point but has nan";
        continue;
      }
      ++seen;
      const Eigen::Vector2d x = s.project(v, P);
      EXPECT_LT((x - t.xy.block<1, 2>(i, 2 * v).transpose()).norm(), 1e-6) << "track " << i << " view " << v;
      EXPECT_TRUE(x.x() >= 0 && x.y() >= 0 && x.x() <= s.params().size - 1 && x.y() <= s.params().size - 1);
    }
    EXPECT_GE(seen, 2) << "track " << i;
  }
}

}  // namespace

TEST(SynthBlock, TwelveViewTruthIsTheProjectionOfEachSeenGroundPoint) {
  const SynthScene s(block_params(12, 4));
  ASSERT_TRUE(s.is_block());
  ASSERT_EQ(s.views(), 12);
  const SynthTruth t = synth_truth_points(s, 400);
  ASSERT_EQ(t.xy.rows(), 400);
  check_truth(s, t);
  // tracks of several lengths, none seen by every view
  std::set<int> lengths;
  for (Eigen::Index i = 0; i < t.xy.rows(); ++i) {
    int c = 0;
    for (int v = 0; v < 12; ++v) c += !std::isnan(t.xy(i, 2 * v));
    lengths.insert(c);
  }
  EXPECT_GE(lengths.size(), 3u);
  EXPECT_LT(*lengths.rbegin(), 12);
  // every view sees some truth points
  for (int v = 0; v < 12; ++v) {
    long n = 0;
    for (Eigen::Index i = 0; i < t.xy.rows(); ++i) n += !std::isnan(t.xy(i, 2 * v));
    EXPECT_GT(n, 20) << "view " << v + 1;
  }
}

TEST(SynthBlock, NeighbouringFootprintsOverlapThirtyToSeventyPercent) {
  for (uint64_t seed : {1, 2, 3, 4, 5, 6, 7, 8}) {
    const SynthScene s(block_params(12, 4, seed));
    const auto nb = synth_neighbours(s);
    EXPECT_EQ(nb.size(), 17u);  // 4 dates x 2 along-track pairs + 3 date pairs x 3 views
    for (const auto& p : nb) {
      const double o = synth_footprint_overlap(s, p.first, p.second);
      EXPECT_GE(o, 0.3) << "seed " << seed << " views " << p.first + 1 << "-" << p.second + 1;
      EXPECT_LE(o, 0.7) << "seed " << seed << " views " << p.first + 1 << "-" << p.second + 1;
      EXPECT_NEAR(o, synth_footprint_overlap(s, p.second, p.first), 1e-12);
    }
    // windows differ: no two views share their footprint; views two dates apart overlap little
    for (int a = 0; a < 12; ++a)
      for (int b = a + 1; b < 12; ++b) {
        EXPECT_LT(synth_footprint_overlap(s, a, b), 0.75) << "seed " << seed << " views " << a + 1 << "-" << b + 1;
        if (b - a >= 6) {
          EXPECT_LT(synth_footprint_overlap(s, a, b), 0.25);
        }
      }
    // each footprint lies in the scene square
    for (int v = 0; v < 12; ++v)
      for (const auto& c : s.footprint(v)) {
        EXPECT_GE(c.minCoeff(), 0);
        EXPECT_LE(c.maxCoeff(), s.scene_size());
      }
  }
}

TEST(SynthBlock, WrittenTruthTracksReadBackWithNanForUnseenViews) {
  SynthParams p = block_params(6, 2);
  p.size = 64;
  p.relief = 5;
  p.points = 40;
  const SynthScene s(p);
  const fs::path dir = fs::temp_directory_path() / ("tpkit-synth-block-write-" + std::to_string(::getpid()));
  SynthWriteOptions w;
  w.threads = 2;
  write_synth_scene(s, dir.string(), w);
  const Tracks t = read_tracks((dir / "truth.tracks").string());
  const SynthTruth truth = synth_truth_points(s, 40);
  ASSERT_EQ(t.size(), 40u);
  ASSERT_EQ(t.views(), 6);
  EXPECT_FALSE(t.complete());
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_GE(t.seen_views(i), 2);
    for (int v = 0; v < 6; ++v) {
      ASSERT_EQ(t.seen(i, v), !std::isnan(truth.xy(static_cast<Eigen::Index>(i), 2 * v)));
      if (t.seen(i, v)) {
        EXPECT_LT((t.point(i, v) - truth.xy.block<1, 2>(static_cast<Eigen::Index>(i), 2 * v).transpose()).norm(), 1e-9);
      }
    }
  }
  for (int v = 1; v <= 6; ++v) EXPECT_TRUE(fs::exists(dir / ("view" + std::to_string(v) + ".tif")));
  EXPECT_FALSE(fs::exists(dir / "truth.trifocal"));
  fs::remove_all(dir);
}

TEST(SynthBlock, FootprintOverlapOfAViewWithItselfIsOne) {
  const SynthScene s(block_params(6, 2));
  for (int v = 0; v < 6; ++v) EXPECT_NEAR(synth_footprint_overlap(s, v, v), 1.0, 1e-9);
}

TEST(SynthBlock, AnglesFollowTheAcquisitions) {
  const SynthScene s(block_params(12, 4));
  for (int v = 0; v < 12; ++v) {
    EXPECT_EQ(s.date_of(v), v / 3);
    EXPECT_EQ(s.index_in_date(v), v % 3);
    const Eigen::Vector3d a = s.view_angles(v);
    const double along = v % 3 == 0 ? 22 : v % 3 == 1 ? 0 : -22;
    EXPECT_NEAR(a[0], along, 0.5 + 1e-9);
    EXPECT_NEAR(a[1], s.view_angles(3 * (v / 3))[1], 1e-12);  // one cross-track angle per date
    EXPECT_GE(std::fabs(a[1]), 3 - 1e-9);
    EXPECT_LE(std::fabs(a[1]), 12 + 1e-9);
  }
  // dates alternate east and west of the ground track
  EXPECT_LT(s.view_angles(0)[1] * s.view_angles(3)[1], 0);
  // --cross-track: one per date, one per view
  SynthParams p = block_params(6, 2);
  p.cross_track = {5, -7};
  const SynthScene s2(p);
  EXPECT_NEAR(s2.view_angles(1)[1], 5, 1e-12);
  EXPECT_NEAR(s2.view_angles(4)[1], -7, 1e-12);
  p.cross_track = {1, 2, 3, 4, 5, 6};
  EXPECT_NEAR(SynthScene(p).view_angles(4)[1], 5, 1e-12);
  p.cross_track = {1, 2, 3};
  EXPECT_THROW(check_params(p), UsageError);
}

TEST(SynthBlock, TwentyFourViewsWork) {
  SynthParams p = block_params(24, 8);
  p.size = 128;
  p.points = 300;
  const SynthScene s(p);
  ASSERT_EQ(s.views(), 24);
  const SynthTruth t = synth_truth_points(s, 300);
  check_truth(s, t);
  for (const auto& nb : synth_neighbours(s)) {
    const double o = synth_footprint_overlap(s, nb.first, nb.second);
    EXPECT_GE(o, 0.3);
    EXPECT_LE(o, 0.7);
  }
  // 24 = 6 dates x 4 views also works (along-track +22, +7.3, -7.3, -22)
  SynthParams q = block_params(24, 6);
  q.size = 128;
  const SynthScene s4(q);
  EXPECT_NEAR(s4.view_angles(1)[0], 22 - 44.0 / 3, 0.5 + 1e-9);
  check_truth(s4, synth_truth_points(s4, 100));
}

TEST(SynthBlock, TriStereoStaysTheDefault) {
  SynthParams p;
  EXPECT_EQ(p.views, 3);
  EXPECT_EQ(synth_dates(p), 1);
  EXPECT_FALSE(synth_is_block(p));
  p.size = 128;
  p.relief = 20;
  const SynthScene s(p);
  EXPECT_EQ(s.views(), 3);
  EXPECT_EQ(synth_neighbours(s).size(), 3u);
  const SynthTruth t = synth_truth_points(s, 50);
  EXPECT_TRUE(t.xy.allFinite());  // every truth point seen by all three views
  // 3 views of 3 dates (one nadir view each) is a block
  SynthParams b = block_params(3, 3);
  EXPECT_TRUE(synth_is_block(b));
  EXPECT_NEAR(SynthScene(b).view_angles(2)[0], 0, 0.5 + 1e-9);
}

TEST(SynthBlock, BadViewsAndDatesAreRefused) {
  auto bad = [](int views, int dates) {
    SynthParams p;
    p.views = views;
    p.dates = dates;
    EXPECT_THROW(check_params(p), UsageError) << views << " views, " << dates << " dates";
  };
  bad(1, 1);
  bad(0, 0);
  bad(97, 0);
  bad(4, 0);   // not a multiple of 3 without --dates
  bad(12, 5);  // not a multiple of the dates
  bad(12, 2);  // 6 views per date
  bad(6, 7);
  SynthParams ok;
  ok.views = 4;
  ok.dates = 2;
  EXPECT_NO_THROW(check_params(ok));
  ok.views = 12;
  ok.dates = 0;
  EXPECT_NO_THROW(check_params(ok));
  EXPECT_EQ(synth_dates(ok), 4);
}

TEST(SynthBlock, ParamsRoundTripGivesTheSameBlock) {
  const SynthParams p = block_params(12, 4);
  const fs::path dir = fs::temp_directory_path() / ("tpkit-synth-block-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  save_params((dir / "scene.params").string(), p);
  const SynthScene a(p), b = SynthScene::load(dir.string());
  EXPECT_EQ(b.views(), 12);
  for (int v = 0; v < 12; ++v) EXPECT_EQ(a.camera(v), b.camera(v));
  // the tri-stereo's params file has no views/dates keys (unchanged bytes)
  SynthParams t;
  save_params((dir / "tri.params").string(), t);
  std::ifstream f(dir / "tri.params");
  std::stringstream ss;
  ss << f.rdbuf();
  EXPECT_EQ(ss.str().find("views"), std::string::npos);
  fs::remove_all(dir);
}

TEST(SynthBlock, ViewBiasTakesAnyViewOfTheBlock) {
  EXPECT_EQ(parse_view_bias("12:1,2", 12).first, 11);
  EXPECT_EQ(parse_view_bias("1:1,2", 12).first, 0);
  EXPECT_THROW(parse_view_bias("13:1,2", 12), UsageError);
  EXPECT_THROW(parse_view_bias("0:1,2", 12), UsageError);
  EXPECT_THROW(parse_view_bias("x:1,2", 12), UsageError);
  EXPECT_THROW(parse_view_bias("4:1,2"), UsageError);  // the tri-stereo: 1 to 3
}

TEST(SynthBlock, RandomBiasStaysWithinItsBoundAndIsSeeded) {
  const SynthScene s(block_params(12, 4));
  const double n1 = s.params().size - 1;
  std::set<double> shifts;
  for (int v = 0; v < 12; ++v) {
    const ImageBias b = synth_random_bias(s, v, 10);
    for (double x : {0.0, n1})
      for (double y : {0.0, n1}) {
        const Eigen::Vector2d d = b.offset({x, y});
        EXPECT_LE(d.cwiseAbs().maxCoeff(), 10.0);
      }
    EXPECT_LE(std::fabs(b.a[0]), 5.0);
    EXPECT_NE(b.a[1], 0);  // affine and drift terms present
    EXPECT_NE(b.b[2], 0);
    const ImageBias again = synth_random_bias(s, v, 10);
    EXPECT_EQ(b.a, again.a);
    shifts.insert(b.a[0]);
  }
  EXPECT_EQ(shifts.size(), 12u);
}

TEST(SynthBlock, EveryViewsRpcFitsItsCameraOverItsFootprint) {
  const SynthScene s(block_params(12, 4));
  const SynthGeoFrame geo(s, SynthGeoOrigin{});
  const SynthTruth t = synth_truth_points(s, 200);
  for (int v : {0, 5, 11}) {
    const ImageBias bias = synth_random_bias(s, v, 10);
    const RpcFit f = synth_view_rpc(s, geo, v, bias);
    EXPECT_LE(f.max_px, 0.01) << "view " << v + 1;
    for (Eigen::Index i = 0; i < t.xy.rows(); ++i) {
      if (std::isnan(t.xy(i, 2 * v))) continue;
      const Eigen::Vector2d truth = t.xy.block<1, 2>(i, 2 * v).transpose();
      // truth pixel = bias applied to the written model's projection (synth_rpc.hpp)
      const Eigen::Vector2d p = bias.apply(f.model.project(geo.to_llh(t.ground.row(i).transpose())));
      EXPECT_LT((p - truth).norm(), 1e-3) << "view " << v + 1 << " track " << i;
    }
  }
}

// The block is well posed for a bias adjustment: biases of up to 10 px (shift, drift, affine) on views 2..12,
// view 1 fixed, noise-free truth tracks of every length: the adjusted models reproject the truth to 0.005 px.
TEST(SynthBlock, AffineAdjustmentOfTheBlockRecoversTheTruth) {
  SynthParams p = block_params(12, 4);
  p.size = 512;
  p.relief = 60;
  const SynthScene s(p);
  const SynthGeoFrame geo(s, SynthGeoOrigin{});
  std::vector<AdjustImage> images(12);
  for (int v = 0; v < 12; ++v) {
    images[v].model = synth_view_rpc(s, geo, v, v == 0 ? ImageBias{} : synth_random_bias(s, v, 10)).model;
    images[v].width = images[v].height = p.size;
    images[v].path = "view" + std::to_string(v + 1) + ".tif";
  }
  images[0].fixed = true;
  const SynthTruth t = synth_truth_points(s, 1500);
  std::vector<AdjustTrack> tracks;
  for (Eigen::Index i = 0; i < t.xy.rows(); ++i) {
    AdjustTrack a;
    a.id = i + 1;
    for (int v = 0; v < 12; ++v)
      if (!std::isnan(t.xy(i, 2 * v))) a.views.emplace_back(v, t.xy.block<1, 2>(i, 2 * v).transpose());
    tracks.push_back(a);
  }
  AdjustOptions o;
  o.model = BiasModel::affine;
  o.threads = 2;
  // a weak prior on the linear terms: this checks the block's geometry, not the prior (the default, 0.01 px/px,
  // pulls the affine terms of these biases, up to 0.005 px/px, enough to leave about 0.02 px on the truth)
  o.prior_linear = 1;
  o.height = dem_height_prior(synth_dem(s, geo, 1.0), 1.0);
  const AdjustResult r = adjust_rpcs(images, tracks, o);
  std::vector<double> s2(12, 0);
  std::vector<long> n(12, 0);
  double sh = 0;
  for (Eigen::Index i = 0; i < t.xy.rows(); ++i) {
    const Eigen::Vector3d g = geo.to_llh(t.ground.row(i).transpose());
    for (int v = 0; v < 12; ++v) {
      if (std::isnan(t.xy(i, 2 * v))) continue;
      const Eigen::Vector2d q = r.bias[v].apply(images[v].model.project(g));
      s2[v] += (q - t.xy.block<1, 2>(i, 2 * v).transpose()).squaredNorm();
      ++n[v];
    }
    sh += std::pow(r.ground[i][2] - g[2], 2);
  }
  for (int v = 0; v < 12; ++v) {
    const double rms = std::sqrt(s2[v] / std::max(1L, n[v]));
    std::cout << "view " << v + 1 << ": " << n[v] << " observations, truth reprojection rms " << rms << " px\n";
    EXPECT_LE(rms, 0.005) << "view " << v + 1;
  }
  const double hrms = std::sqrt(sh / t.xy.rows());
  std::cout << "height rms " << hrms << " m\n";
  EXPECT_LE(hrms, 0.25);
}
