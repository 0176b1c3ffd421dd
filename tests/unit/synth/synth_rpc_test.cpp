// tp-synth's RPCs: each view's fitted RPC00B reproduces its camera to 0.01 px over the scene volume; an
// injected image-space bias is exactly what rpc-adjust must recover: with two views biased (shift up to
// 10 px, drift and affine terms) and the third fixed, the adjusted models project the truth ground points
// to the truth pixels within 0.02 px RMS and the tracks' heights come within 0.25 m RMS (noise-free tracks,
// default scene: 1024 px, 0.5 m GSD; the DEM of the scene as the height prior that fixes the datum).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_ground.hpp"
#include "tpkit/synth/synth_rpc.hpp"
#include "tpkit/synth/synth_scene.hpp"

using namespace tpkit;

namespace {
SynthScene scene_of(const std::string& camera) {
  SynthParams p;
  p.camera = camera;
  return SynthScene(p);
}
}  // namespace

TEST(SynthRpc, FittedModelsReproduceTheCamerasOverTheVolume) {
  for (const char* camera : {"affine", "perspective"}) {
    SynthScene scene = scene_of(camera);
    SynthGeoFrame geo(scene, SynthGeoOrigin{});
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    const double S = scene.scene_size(), r = 0.5 * scene.params().relief;
    for (int v = 0; v < 3; ++v) {
      RpcFit f = synth_view_rpc(scene, geo, v);
      EXPECT_LE(f.max_px, 0.01) << camera << " view " << v + 1;
      double worst = 0;
      for (int k = 0; k < 3000; ++k) {
        Eigen::Vector3d X(u(rng) * S, u(rng) * S, (2 * u(rng) - 1) * r);
        Eigen::Vector3d g = geo.to_llh(X);
        worst = std::max(worst, (f.model.project(g) - scene.project(v, X)).norm());
      }
      EXPECT_LE(worst, 0.01) << camera << " view " << v + 1;
    }
  }
}

TEST(SynthRpc, GeoFrameRoundTripsAndSitsAtTheOrigin) {
  SynthScene scene = scene_of("affine");
  SynthGeoFrame geo(scene, SynthGeoOrigin{43.3, 5.4, 100});
  const double S = scene.scene_size();
  Eigen::Vector3d c = geo.to_llh({S / 2, S / 2, 0});
  EXPECT_NEAR(c[0], 5.4, 1e-12);
  EXPECT_NEAR(c[1], 43.3, 1e-12);
  EXPECT_NEAR(c[2], 100, 1e-9);
  Eigen::Vector3d X(12.5, 400, -30);
  EXPECT_LT((geo.from_llh(geo.to_llh(X)) - X).norm(), 1e-8);
}

TEST(SynthRpc, InjectedBiasIsTheCorrectionToTheTruth) {
  SynthScene scene = scene_of("affine");
  SynthGeoFrame geo(scene, SynthGeoOrigin{});
  ImageBias b = parse_image_bias("6,-8,0.002,-0.001,0.001,0.0015", "--rpc-bias");
  RpcFit f = synth_view_rpc(scene, geo, 1, b);
  EXPECT_LE(f.max_px, 0.01);
  Eigen::Vector3d X(100, 200, 10);
  Eigen::Vector2d q = f.model.project(geo.to_llh(X));
  EXPECT_NEAR((b.apply(q) - scene.project(1, X)).norm(), 0, 1e-6);
}

namespace {
struct Recovery {
  double rms_px = 0, height_rms = 0;
  std::vector<ImageBias> bias;
};

Recovery adjust_synthetic(BiasModel model, const std::map<int, ImageBias>& injected, long outliers = 0,
                          long* flagged = nullptr) {
  SynthScene scene = scene_of("affine");
  SynthGeoFrame geo(scene, SynthGeoOrigin{});
  std::vector<AdjustImage> images(3);
  for (int v = 0; v < 3; ++v) {
    auto it = injected.find(v);
    images[v].model = synth_view_rpc(scene, geo, v, it == injected.end() ? ImageBias{} : it->second).model;
    images[v].width = images[v].height = scene.params().size;
    images[v].path = "view" + std::to_string(v + 1) + ".tif";
  }
  images[0].fixed = true;
  SynthTruth truth = synth_truth_points(scene, 2000);
  std::vector<AdjustTrack> tracks;
  for (Eigen::Index t = 0; t < truth.xy.rows(); ++t) {
    AdjustTrack a;
    a.id = t + 1;
    for (int v = 0; v < 3; ++v) a.views.emplace_back(v, truth.xy.block<1, 2>(t, 2 * v).transpose());
    if (t < outliers) a.views[1].second += Eigen::Vector2d(4, -3);  // a gross mismatch in view 2
    tracks.push_back(a);
  }
  AdjustOptions o;
  o.model = model;
  o.height = dem_height_prior(synth_dem(scene, geo, 1.0), 1.0);
  AdjustResult r = adjust_rpcs(images, tracks, o);
  if (flagged) {
    // a track of three views with one wrong view loses that view (rpc_adjust.hpp), not the track: each
    // outlier track keeps views 1 and 3 and is not flagged; no good track loses a view
    *flagged = std::count(r.flagged.begin(), r.flagged.end(), 1);
    for (long t = 0; t < static_cast<long>(tracks.size()); ++t)
      EXPECT_EQ(r.views_dropped[t], t < outliers ? 1 : 0) << "track " << t + 1;
    EXPECT_EQ(r.dropped_views, outliers);
    EXPECT_EQ(r.ground.size(), tracks.size());  // kept, not dropped
  }
  Recovery out;
  out.bias = r.bias;
  // the adjusted models as rpc-adjust writes them (bias folded into a refitted RPC00B)
  std::vector<RpcModel> adjusted;
  for (int v = 0; v < 3; ++v)
    adjusted.push_back(fold_bias(images[v].model, r.bias[v], images[v].width, images[v].height, 0, 200).model);
  double s = 0, sh = 0;
  for (Eigen::Index t = 0; t < truth.xy.rows(); ++t) {
    Eigen::Vector3d g = geo.to_llh(truth.ground.row(t).transpose());
    for (int v = 0; v < 3; ++v) s += (adjusted[v].project(g) - truth.xy.block<1, 2>(t, 2 * v).transpose()).squaredNorm();
    sh += std::pow(r.ground[t][2] - g[2], 2);
  }
  out.rms_px = std::sqrt(s / (3.0 * truth.xy.rows()));
  out.height_rms = std::sqrt(sh / truth.xy.rows());
  return out;
}
}  // namespace

TEST(SynthRpc, AffineAdjustmentRecoversInjectedBiases) {
  std::map<int, ImageBias> injected = {{1, parse_image_bias("6,-8,0.002,-0.001,0.001,0.0015", "b")},
                                       {2, parse_image_bias("-10,4,0.001,0.0005,-0.0008,0.0004", "b")}};
  Recovery r = adjust_synthetic(BiasModel::affine, injected);
  std::cout << "affine: truth reprojection rms " << r.rms_px << " px, height rms " << r.height_rms << " m\n";
  EXPECT_LE(r.rms_px, 0.02);
  EXPECT_LE(r.height_rms, 0.25);
  for (int v = 1; v < 3; ++v) {
    EXPECT_NEAR(r.bias[v].a[0], injected[v].a[0], 0.05);
    EXPECT_NEAR(r.bias[v].b[0], injected[v].b[0], 0.05);
  }
}

TEST(SynthRpc, ShiftAdjustmentRecoversInjectedShifts) {
  std::map<int, ImageBias> injected = {{1, parse_image_bias("7.5,-3", "b")}, {2, parse_image_bias("-2,9.5", "b")}};
  Recovery r = adjust_synthetic(BiasModel::shift, injected);
  std::cout << "shift: truth reprojection rms " << r.rms_px << " px, height rms " << r.height_rms << " m\n";
  EXPECT_LE(r.rms_px, 0.02);
  EXPECT_LE(r.height_rms, 0.25);
}

TEST(SynthRpc, GrossMismatchesLoseTheirViewAndDoNotSpoilTheFit) {
  std::map<int, ImageBias> injected = {{1, parse_image_bias("6,-8,0.002,-0.001", "b")}, {2, parse_image_bias("-10,4", "b")}};
  long flagged = 0;
  Recovery r = adjust_synthetic(BiasModel::affine, injected, 20, &flagged);
  EXPECT_EQ(flagged, 0);
  std::cout << "20 outliers of 5 px: truth reprojection rms " << r.rms_px << " px, height rms " << r.height_rms << " m\n";
  EXPECT_LE(r.rms_px, 0.02);  // the Huber loss keeps them from pulling the biases
  EXPECT_LE(r.height_rms, 0.25);
}
