#include "tpkit/synth/synth_conditions.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "tpkit/synth/synth_noise.hpp"

namespace tpkit {

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180;

// Two octaves of value noise in about [-1, 1] at the scale `L` metres.
double field(uint64_t seed, double X, double Y, double L) {
  return 0.7 * synth::value_noise(seed, X / L, Y / L) + 0.3 * synth::value_noise(seed ^ 0x5bd1e995ULL, 3.1 * X / L, 3.1 * Y / L);
}

// Soft cover in [0, 1] of about `fraction` of the ground: the field above a threshold chosen so that a
// field spread evenly over [-0.8, 0.8] exceeds it over that fraction, with a shore 0.06 wide.
double cover(double f, double fraction) {
  const double t = 0.8 - 1.6 * fraction;
  return synth::smoothstep(t - 0.06, t + 0.06, f);
}

const Eigen::Vector3d& second_sun() {
  static const Eigen::Vector3d s(std::cos(35 * kDeg) * std::cos(120 * kDeg), std::cos(35 * kDeg) * std::sin(120 * kDeg),
                                 std::sin(35 * kDeg));
  return s;
}
}  // namespace

const Eigen::Vector3d& synth_second_sun() { return second_sun(); }

bool synth_has_conditions(const SynthParams& p) { return p.date2 != 0 || p.clouds != 0 || p.water != 0 || p.nodata != 0; }

double synth_condition_radiance(const SynthScene& scene, int view, double X, double Y, const Eigen::Vector2d& g) {
  const SynthParams& p = scene.params();
  const uint64_t seed = synth::hash(p.seed, 0xc0d1);
  double land;
  if (view > 0 && p.date2 > 0) {
    const double d = p.date2;
    const double veg = synth::smoothstep(0.0, 0.3, field(synth::hash(seed, 1), X, Y, 25));       // patches ~40 %
    const double tex2 = 0.3 + 0.18 * field(synth::hash(seed, 2), X, Y, 1.5);                    // their new texture
    const double a = synth::lerp(scene.albedo(X, Y), tex2, d * veg);
    const double season = 1 + 0.35 * d * field(synth::hash(seed, 3), X, Y, 60);
    const Eigen::Vector3d nrm = Eigen::Vector3d(-g.x(), -g.y(), 1).normalized();
    land = a * season * (0.3 + 0.7 * std::max(0.0, nrm.dot(second_sun())));
  } else {
    land = scene.radiance(X, Y, g);
  }
  if (p.water > 0) {
    const double w = cover(field(synth::hash(seed, 4), X, Y, 40), p.water);
    land = synth::lerp(land, view > 0 && p.date2 > 0 ? 0.08 : 0.06, w);
  }
  if (view > 0 && p.clouds > 0) {
    const uint64_t cs = synth::hash(seed, 5, view);
    // the shadow: the cloud cover 40 m towards the sun (the cloud that shades (X, Y))
    const Eigen::Vector2d towards_sun = second_sun().head<2>().normalized() * 40.0;
    const double shadow = cover(field(cs, X + towards_sun.x(), Y + towards_sun.y(), 35), p.clouds);
    land *= 1 - 0.6 * shadow;
    const double c = cover(field(cs, X, Y, 35), p.clouds);
    land = synth::lerp(land, 0.95 + 0.05 * synth::value_noise(synth::hash(cs, 6), X / 4, Y / 4), c);
  }
  return land;
}

double synth_condition_dn(const SynthParams& p, int view, long x, double dn) {
  if (view == 0) return dn;
  if (p.nodata > 0 && x < static_cast<long>(std::lround(p.nodata * static_cast<double>(p.size)))) return 0;
  if (p.date2 > 0) dn = 4095 * std::pow(std::clamp(dn / 4095, 0.0, 1.0), 1 / (1 + 0.6 * p.date2));
  return std::max(dn, 1.0);  // 0 is nodata
}

}  // namespace tpkit
