// rpc-adjust with ground control points (issue 25). Models: the real Pléiades crops' tag 50844, NONE
// fixed; truth: ground points on a grid over image 1 on a smooth terrain, projected through each model
// and moved by a known bias on EVERY image (observed = bias(rpc(g)), pixels x column, y row). Tie points
// alone cannot see a common shift; five control points (corners and centre) hold it.
#include <gtest/gtest.h>

#include <cmath>

#include "tpkit/core/error.hpp"
#include "tpkit/ground/gcp_file.hpp"
#include "tpkit/ground/ground_accuracy.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "pleiades_models.hpp"

using namespace tpkit;

namespace {

using Truth = tpkit_test::BiasedTruth;

// n x n ground points over image 1 (fractions 0.05 .. 0.95 of its size), seen in all three images.
Truth truth(int n) {
  Truth T;
  T.images = tpkit_test::pleiades_images();
  T.bias.resize(3);
  T.bias[0].a = {5.0, 0.0003, 0.0001};
  T.bias[0].b = {-4.0, -0.0002, 0.0002};
  T.bias[1].a = {3.0, 0.0004, -0.0002};
  T.bias[1].b = {-2.0, 0.0001, 0.0003};
  T.bias[2].a = {-4.0, -0.0003, 0.0001};
  T.bias[2].b = {1.5, 0.0002, -0.0004};
  tpkit_test::add_grid_points(T, n, 0.05 * T.images[0].width, 0.05 * T.images[0].height);
  return T;
}

std::vector<AdjustTrack> ties(const Truth& T) {
  std::vector<AdjustTrack> out;
  for (size_t p = 0; p < T.ground.size(); ++p) {
    AdjustTrack t;
    t.source = "ties";
    t.id = static_cast<long long>(p) + 1;
    for (int i = 0; i < 3; ++i) t.views.emplace_back(i, T.xy[p][i]);
    out.push_back(t);
  }
  return out;
}

// control points: truth points nearest the corners and the centre of the grid (exact positions and
// measurements), ground sigma 0.3 m, image sigma 0.2 px; `blunder_east` metres added to the first's east
std::vector<AdjustControl> controls(const Truth& T, double blunder_east = 0) {
  std::vector<AdjustControl> out;
  const size_t n = T.ground.size();
  for (size_t p : {size_t{0}, n - 1, n / 2, n / 9, n - n / 9}) {
    AdjustControl c;
    c.source = "controls";
    c.id = static_cast<long long>(p) + 1;
    c.llh = T.ground[p];
    c.sigma_enu = Eigen::Vector3d::Constant(0.3);
    for (int i = 0; i < 3; ++i) {
      c.views.emplace_back(i, T.xy[p][i]);
      c.sigma_px.push_back(0.2);
    }
    out.push_back(c);
  }
  const double metres_per_deg_lon = 111412.84 * std::cos(out[0].llh[1] * M_PI / 180);
  out[0].llh[0] += blunder_east / metres_per_deg_lon;
  return out;
}

// RMS over the truth points of |adjusted bias(rpc(g)) - truth pixel| in image i (px)
double truth_rms(const Truth& T, const AdjustResult& r, int i) {
  double s = 0;
  for (size_t p = 0; p < T.ground.size(); ++p) s += (r.bias[i].apply(T.images[i].model.project(T.ground[p])) - T.xy[p][i]).squaredNorm();
  return std::sqrt(s / T.ground.size());
}

}  // namespace

// With five control points and no image fixed, every image's bias (shift, drift, affine terms) is
// recovered: the adjusted models put the truth ground points on their truth pixels. Without them the
// common shift is the bias priors' smallest-bias choice, pixels away from the truth.
TEST(GcpAdjust, ControlPointsHoldTheGaugeWithNoImageFixed) {
  const Truth T = truth(12);
  ASSERT_GT(T.ground.size(), 60u);
  AdjustOptions o;
  o.model = BiasModel::affine;
  const auto tracks = ties(T);
  const AdjustResult free_fit = adjust_rpcs(T.images, tracks, o);
  o.control = controls(T);
  const AdjustResult r = adjust_rpcs(T.images, tracks, o);
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(truth_rms(T, r, i), 0.05) << "image " << i + 1;
    EXPECT_GT(truth_rms(T, free_fit, i), 1.0) << "image " << i + 1;  // what the GCPs fixed
  }
  // the adjusted control points sit at their (exact) known positions
  for (size_t c = 0; c < o.control.size(); ++c) EXPECT_LT(enu_error(r.control_ground[c], o.control[c].llh).norm(), 0.05);
  // every truth point, intersected on the adjusted models as a check point would be, within 5 cm
  std::vector<AdjustControl> checks;
  for (size_t p = 0; p < T.ground.size(); p += 7) {
    AdjustControl c;
    c.llh = T.ground[p];
    for (int i = 0; i < 3; ++i) c.views.emplace_back(i, T.xy[p][i]), c.sigma_px.push_back(0.2);
    checks.push_back(c);
  }
  const ControlEvaluation after = evaluate_controls(T.images, &r.bias, checks);
  const ControlEvaluation before = evaluate_controls(T.images, nullptr, checks);
  std::vector<Eigen::Vector3d> ea, eb;
  for (size_t k = 0; k < checks.size(); ++k) {
    ASSERT_TRUE(after.intersection[k].ok);
    ea.push_back(enu_error(after.intersection[k].llh, checks[k].llh));
    eb.push_back(enu_error(before.intersection[k].llh, checks[k].llh));
    for (const auto& d : after.known_residual_px[k]) EXPECT_LT(d.norm(), 0.05);
  }
  const AccuracyStats sa = accuracy_stats(ea), sb = accuracy_stats(eb);
  EXPECT_LT(sa.rmse_r, 0.05);
  EXPECT_LT(sa.rmse_u, 0.05);
  EXPECT_GT(sb.rmse_r + sb.rmse_u, 1.0);  // the delivered (biased) models are metres off
  // consistent control points agree with the tie points
  const GcpCheck ok = check_gcps(T.images, tracks, o, r);
  EXPECT_FALSE(ok.contradicts) << ok.figures;
}

// A control point 20 m off in the east contradicts the others and the tie points: found, with that point
// named and its residual in metres.
TEST(GcpAdjust, ABlunderedControlPointIsFound) {
  const Truth T = truth(10);
  AdjustOptions o;
  o.control = controls(T, 20);
  const auto tracks = ties(T);
  const AdjustResult r = adjust_rpcs(T.images, tracks, o);
  const GcpCheck c = check_gcps(T.images, tracks, o, r);
  EXPECT_TRUE(c.contradicts) << c.figures;
  EXPECT_EQ(c.worst_id, o.control[0].id);
  EXPECT_GT(c.worst_normalized, 5);
  EXPECT_GT(std::fabs(c.worst_enu[0]), 1.0);
}

// gcps_to_adjust: images matched by file name; an unknown image, a measurement off its image and a
// check point in one image are errors naming file:line.
TEST(GcpAdjust, MeasurementsAreMatchedAndCheckedWithFileAndLine) {
  const auto images = tpkit_test::pleiades_images();
  const std::string text =
      "1 43.3 5.4 150 0.3 0.3 0.5 img_01.tif 100 200 0.2 0.2 img_02.tif 110 210 0.2 0.2\n"
      "2 43.3 5.4 150 0.3 0.3 0.5 img_03.tif 10 20 0.2 0.2\n";
  const auto gcps = parse_asp_gcp(text, "a.gcp");
  const auto c = gcps_to_adjust(gcps, GcpRole::control, images);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].views[1].first, 1);
  EXPECT_EQ(c[1].views[0].first, 2);
  EXPECT_EQ(c[0].views[0].second, Eigen::Vector2d(100, 200));
  auto error_of = [&](const std::string& t, GcpRole role) { return tpkit_test::message([&] { gcps_to_adjust(parse_asp_gcp(t, "b.gcp"), role, images); }); };
  EXPECT_NE(error_of("1 43.3 5.4 150 1 1 1 img_01.tif 1 2 0.2 0.2\n7 43.3 5.4 150 1 1 1 nothere.tif 1 2 0.2 0.2\n", GcpRole::control).find("b.gcp:2:"), std::string::npos);
  EXPECT_NE(error_of("7 43.3 5.4 150 1 1 1 img_01.tif -3 2 0.2 0.2\n", GcpRole::control).find("off"), std::string::npos);
  EXPECT_NE(error_of("7 43.3 5.4 150 1 1 1\n", GcpRole::control).find("b.gcp:1:"), std::string::npos);
}
