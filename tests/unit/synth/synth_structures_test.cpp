// Buildings and trees of tp-synth (synth_structures.hpp): the surface has vertical walls, a point hidden
// behind a wall or crown is reported invisible (against an independent march through the surface model),
// cast shadows agree with a march towards each date's sun and move with it, the truth lies on the surface
// and is seen where it says, the fast renderer agrees with the per-sample reference, and a scene without
// structures is the scene it was.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "tpkit/core/error.hpp"
#include "tpkit/synth/synth_render.hpp"
#include "tpkit/synth/synth_scene.hpp"
#include "tpkit/synth/synth_structures.hpp"

using namespace tpkit;

namespace {

SynthParams town(double buildings, double trees) {
  SynthParams p;
  p.seed = 5;
  p.size = 256;
  p.relief = 30;
  p.gsd = 0.5;
  p.points = 200;
  p.buildings = buildings;
  p.trees = trees;
  return p;
}

// Independent of the ray casts: with buildings only, the surface is the height field height() (a box is a
// column), so a straight segment from X towards `dir` is blocked when one of its samples (every 2 cm from 1 cm, up
// to the highest roof) lies clearly below height() there.
bool march_blocked(const SynthScene& s, const Eigen::Vector3d& X, const Eigen::Vector3d& dir, double ztop) {
  const double len = (ztop - X.z()) / dir.z();
  for (double t = 0.01; t < len; t += 0.02) {
    const Eigen::Vector3d p = X + t * dir;
    if (p.z() < s.height(p.x(), p.y()) - 1e-6) return true;
  }
  return false;
}

}  // namespace

TEST(SynthStructures, SurfaceHasVerticalWalls) {
  const SynthScene s(town(0.6, 0));
  ASSERT_GT(s.structures().buildings(), 20);
  // Along lines across the scene, height() jumps by >= 6 m (the lowest building) at walls: a jump that stays
  // when its bracket shrinks to 1 micrometre is a discontinuity, not a steep slope.
  const double S = s.scene_size();
  int walls = 0;
  for (int line = 0; line < 20; ++line) {
    const double Y = S * (line + 0.5) / 20;
    double xprev = 0, zprev = s.height(0, Y);
    for (double X = 0.05; X <= S; X += 0.05) {
      const double z = s.height(X, Y);
      if (std::abs(z - zprev) > 5) {
        double a = xprev, b = X, za = zprev, zb = z;
        while (b - a > 1e-6) {
          const double m = 0.5 * (a + b), zm = s.height(m, Y);
          if (std::abs(zm - za) > std::abs(zm - zb)) b = m, zb = zm; else a = m, za = zm;
        }
        EXPECT_GT(std::abs(zb - za), 5.9) << "line " << line << " X " << X;
        ++walls;
      }
      xprev = X;
      zprev = z;
    }
  }
  EXPECT_GT(walls, 40);
  // The tilted views see walls: surfaces of kind wall with a horizontal normal, the surface's own height
  // below the roof there.
  int seen = 0;
  for (int y = 0; y < 256; y += 4)
    for (int x = 0; x < 256; x += 4) {
      const auto f = s.surface(0, x, y);
      ASSERT_TRUE(f.has_value());
      if (f->kind != SynthStructures::kWall) continue;
      ++seen;
      EXPECT_EQ(f->normal.z(), 0.0);
      EXPECT_NEAR(f->normal.norm(), 1.0, 1e-12);
      // just outside the wall the surface is lower than the hit; just inside it, the roof above it
      const Eigen::Vector3d out = f->X + 0.01 * f->normal, in = f->X - 0.01 * f->normal;
      EXPECT_LT(s.height(out.x(), out.y()), f->X.z());
      EXPECT_GT(s.height(in.x(), in.y()), f->X.z());
    }
  EXPECT_GT(seen, 50);
}

TEST(SynthStructures, OccludedPointsAreInvisible) {
  const SynthScene s(town(0.6, 0));
  const double ztop = s.structures().zmax() + 1;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, s.scene_size());
  int hidden = 0, seen = 0, total = 0;
  for (int k = 0; k < 400; ++k) {
    Eigen::Vector3d X(u(rng), u(rng), 0);
    X.z() = s.height(X.x(), X.y());
    for (int v = 0; v < 3; ++v) {
      const Eigen::Vector2d x = s.project(v, X);
      if (!(x.x() >= 0 && x.y() >= 0 && x.x() <= 255 && x.y() <= 255)) continue;
      Eigen::Vector3d o, d;
      s.ray(v, x.x(), x.y(), o, d);
      const bool blocked = march_blocked(s, X, -d, ztop);
      const bool vis = s.visible(v, X);
      EXPECT_EQ(vis, !blocked) << "point " << k << " view " << v << " at " << X.transpose();
      hidden += !vis;
      seen += vis;
      ++total;
      // where it is hidden, the first surface on its ray is something else, nearer the sensor
      if (!vis) {
        const auto g = s.ground_point(v, x.x(), x.y());
        ASSERT_TRUE(g.has_value());
        EXPECT_GT((*g - X).norm(), 0.05);
        EXPECT_LT((*g - o).dot(d), (X - o).dot(d));
      }
    }
  }
  std::cerr << "occlusion: " << hidden << " of " << total << " surface points hidden behind walls\n";
  EXPECT_GT(hidden, total / 50);
  EXPECT_GT(seen, total / 2);
}

TEST(SynthStructures, CrownsHideWhatIsUnderThem) {
  // A ground point straight under a crown lobe's centre is hidden from the nadir view; the crown's top seen.
  const SynthScene s(town(0, 0.8));
  ASSERT_GT(s.structures().trees(), 20);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0, s.scene_size());
  int crowns = 0;
  for (int k = 0; k < 3000 && crowns < 40; ++k) {
    const double X = u(rng), Y = u(rng);
    const double top = s.structures().top(X, Y);
    if (!std::isfinite(top) || top < s.height(X, Y) - 1e-9) continue;
    const Eigen::Vector3d P(X, Y, top);
    if (!s.visible(1, P)) continue;  // (another crown in front)
    ++crowns;
    // the ground below, more than 2 m under the crown's top, is hidden from the nadir view
    const Eigen::Vector2d x = s.project(1, P);
    const auto g = s.surface(1, x.x(), x.y());
    ASSERT_TRUE(g.has_value());
    EXPECT_EQ(g->kind, SynthStructures::kTree);
    EXPECT_LT((g->X - P).norm(), 1e-6);
    EXPECT_FALSE(s.visible(1, Eigen::Vector3d(X, Y, top - 2)));
  }
  EXPECT_GE(crowns, 40);
}

TEST(SynthStructures, ShadowsAgreeWithMarchAndMoveWithTheSun) {
  // Two dates, one view each: each date's sun casts the buildings' shadows.
  SynthParams p = town(0.6, 0);
  p.views = 2;
  p.dates = 2;
  const SynthScene s(p);
  const Eigen::Vector3d s0 = s.sun(0), s1 = s.sun(1);
  EXPECT_GT(std::acos(std::clamp(s0.dot(s1), -1.0, 1.0)) * 180 / 3.14159265358979, 15);
  const double ztop = s.structures().zmax() + 1;
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0, s.scene_size());
  int shade0 = 0, shade1 = 0, differ = 0, n = 0;
  for (int k = 0; k < 600; ++k) {
    const double X = u(rng), Y = u(rng);
    if (std::isfinite(s.structures().top(X, Y))) continue;  // ground points only
    const Eigen::Vector3d P(X, Y, s.height(X, Y));
    const Eigen::Vector2d g = s.height_gradient(X, Y);
    const Eigen::Vector3d nrm = Eigen::Vector3d(-g.x(), -g.y(), 1).normalized();
    const bool a = s.in_shadow(0, P, nrm), b = s.in_shadow(1, P, nrm);
    EXPECT_EQ(a, march_blocked(s, P + 1e-3 * nrm, s0, ztop)) << X << " " << Y;
    EXPECT_EQ(b, march_blocked(s, P + 1e-3 * nrm, s1, ztop)) << X << " " << Y;
    shade0 += a;
    shade1 += b;
    differ += a != b;
    ++n;
    // a shadowed ground point gets the ambient light only
    SynthSurface f;
    f.X = P;
    f.normal = nrm;
    if (a) {
      EXPECT_NEAR(s.surface_radiance(0, f), 0.3 * s.albedo(X, Y), 1e-12);
    }
  }
  std::cerr << "shadows: date 1 " << shade0 << ", date 2 " << shade1 << ", differ " << differ << " of " << n << " ground points\n";
  EXPECT_GT(shade0, n / 20);
  EXPECT_GT(shade1, n / 20);
  EXPECT_GT(differ, n / 20);
}

TEST(SynthStructures, TruthOnTheSurfaceAndVisible) {
  const SynthScene s(town(0.45, 0.35));
  const SynthTruth t = synth_truth_points(s, 300);
  int roofs = 0, crowns = 0;
  for (Eigen::Index i = 0; i < t.ground.rows(); ++i) {
    const Eigen::Vector3d X = t.ground.row(i).transpose();
    EXPECT_NEAR(X.z(), s.height(X.x(), X.y()), 1e-9);
    for (int v = 0; v < 3; ++v) {
      EXPECT_TRUE(s.visible(v, X));
      EXPECT_LT((s.project(v, X) - t.xy.block<1, 2>(i, 2 * v).transpose()).norm(), 1e-9);
      // the view's ray through the truth pixel meets the surface at X: the truth is what the image shows
      const auto g = s.ground_point(v, t.xy(i, 2 * v), t.xy(i, 2 * v + 1));
      ASSERT_TRUE(g.has_value());
      EXPECT_LT((*g - X).norm(), 1e-6) << "track " << i << " view " << v;
    }
    const double top = s.structures().top(X.x(), X.y());
    if (std::isfinite(top) && std::abs(top - X.z()) < 1e-9) {
      const auto f = s.surface(1, t.xy(i, 2), t.xy(i, 3));
      (f->kind == SynthStructures::kRoof ? roofs : crowns) += 1;
    }
  }
  std::cerr << "truth: " << roofs << " on roofs, " << crowns << " on crowns of " << t.ground.rows() << "\n";
  EXPECT_GT(roofs, 30);
  EXPECT_GT(crowns, 5);
}

TEST(SynthStructures, FastRenderingAgreesWithReference) {
  // render_rows against an exact cast of every sample (synth_render.hpp), noise off. Walls, roof and crown
  // edges and cast shadows are discontinuities: with structures the nodes are the samples themselves
  // (synth_box_node_filter), so only the Newton positions (1e-4 m) and the order of the sums differ
  // (measured 0.06 and 0 DN RMS, no pixel off by more than 1 DN; the Catmull-Rom lattice of the default
  // scene gave 17.7 and 6.0 DN RMS here, 27 pixels off by more than 100 DN).
  SynthParams p = town(0.45, 0.35);
  p.noise = 0;
  p.size = 160;
  const SynthScene s(p);
  for (int v : {0, 1}) {
    const long y0 = 50, rows = 16;
    std::vector<uint16_t> fast(static_cast<size_t>(rows) * p.size), ref(fast.size());
    s.render_rows(v, y0, rows, fast.data());
    synth_reference_rows(s, v, y0, rows, ref.data());
    double ss = 0;
    long far = 0;
    for (size_t i = 0; i < fast.size(); ++i) {
      const double e = static_cast<double>(fast[i]) - ref[i];
      ss += e * e;
      far += std::abs(e) > 10;
    }
    const double rms = std::sqrt(ss / static_cast<double>(fast.size()));
    std::cerr << "view " << v << ": fast - exact rms " << rms << " DN, " << far << " of " << fast.size() << " pixels off by > 10 DN\n";
    EXPECT_LT(rms, 0.5) << "view " << v;
    EXPECT_LE(far, static_cast<long>(fast.size()) / 500) << "view " << v;
  }
}

TEST(SynthStructures, NoneByDefaultAndParamsRoundTrip) {
  SynthParams p = town(0, 0);
  EXPECT_FALSE(SynthScene(p).has_structures());
  apply_scene_preset("buildings", p);
  EXPECT_EQ(p.buildings, 0.45);
  EXPECT_EQ(p.trees, 0.35);
  EXPECT_THROW(apply_scene_preset("castle", p), UsageError);
  // scene.params keeps them, and the scene loaded from it is the same town
  const std::string path = ::testing::TempDir() + "/structures.params";
  save_params(path, p);
  const SynthParams q = load_params(path);
  EXPECT_EQ(q.buildings, 0.45);
  EXPECT_EQ(q.trees, 0.35);
  const SynthScene a(p), b(q);
  EXPECT_EQ(a.structures().buildings(), b.structures().buildings());
  EXPECT_EQ(a.structures().trees(), b.structures().trees());
  EXPECT_EQ(a.height(40.3, 51.7), b.height(40.3, 51.7));
  p.buildings = 1.5;
  EXPECT_THROW(check_params(p), UsageError);
}
