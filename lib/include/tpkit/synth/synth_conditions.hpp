// Conditions of a synthetic scene (tp-synth --second-date, --clouds, --water, --nodata-band): how the
// views of a pair taken on different dates and in different weather disagree. They change the radiometry
// only: every view keeps its camera, so the truth (tracks, cameras, RPCs) stays exact; a truth track may
// then lie under a cloud, on water or in nodata, where no image can match it.
//
// Conventions: fields are functions of the ground position (X, Y in metres, synth_scene.hpp) and of the
// scene's seed (clouds: and of the view), so that every sample of every strip and thread sees the same
// value. View 0 (view1.tif) is the reference date: it gets water only. Views 1.. (view2.tif ..) get:
//  - second date (strength d in 0..1): vegetation-like patches (about 40 % of the ground) whose albedo is
//    replaced by a different fine texture (weight d), a seasonal multiplicative field 1 + 0.35 d n(X/60 m),
//    shading by another sun (azimuth 120 deg, elevation 35 deg, the reference sun being at 200..240 deg,
//    55 deg), and a non-linear tone curve DN' = 4095 (DN / 4095)^(1 / (1 + 0.6 d)) on the 12-bit DN;
//  - clouds: a bright, textured layer (radiance 0.9..1) over about the given fraction of the ground,
//    and its shadow (radiance x 0.4 under full cover) cast 40 m away against the second sun's azimuth;
//  - nodata: the left `nodata` fraction of the columns is DN 0 (tp-match --nodata 0 reads it as nodata).
// Water (every view): about the given fraction of the ground is a featureless surface of radiance 0.06
// (0.08 at the second date: a specular glint) with a soft shore.
#pragma once
#include <Eigen/Core>
#include <cstdint>

#include "tpkit/synth/synth_scene.hpp"

namespace tpkit {

// Unit vector towards the second date's sun (azimuth 120 deg, elevation 35 deg; ground frame).
const Eigen::Vector3d& synth_second_sun();

// True when p sets any condition (the default scene: false, and render_rows is as before).
bool synth_has_conditions(const SynthParams& p);

// Radiance (as SynthScene::radiance, about [0, 1]) of the ground at (X, Y) with terrain gradient g seen in
// `view` under the scene's conditions.
double synth_condition_radiance(const SynthScene& scene, int view, double X, double Y, const Eigen::Vector2d& g);

// The 12-bit DN of pixel column x of `view` after the sensor-level conditions (tone curve, nodata band):
// `dn` is the rendered DN (gain x radiance + offset + noise, not yet rounded).
double synth_condition_dn(const SynthParams& p, int view, long x, double dn);

}  // namespace tpkit
