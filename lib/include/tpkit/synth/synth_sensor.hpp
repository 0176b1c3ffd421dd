// Sensors of a synthetic scene's views 2..N (tp-synth --blur, --resolution-ratio, --rotation): a pair from
// another satellite than view 1's (view1.tif, the reference), coarser, blurred or flown on another orbit.
//  - blur SIGMA (pixels of the view): a Gaussian point spread function (a coarser sensor resampled). Order
//    per pixel: mean radiance over the pixel (box response, SynthScene::render_rows of the scene seen by
//    ideal sensors), gain, offset and the second date's tone curve, rounded to the 12-bit DN; then the PSF
//    (OpenCV's Gaussian, kernel radius ceil(3 SIGMA), the image's edge rows and columns repeated beyond it);
//    then the sensor noise (sigma SynthParams::noise, its own seeded stream), the nodata band, rounding.
//    Radiometric only: the cameras, and so the truth, are unchanged.
//  - resolution ratio R (1..4): the focal length divided by R, so each pixel spans R times the ground it
//    would with view 1's sensor; the image keeps its size, so it sees about R^2 times the ground area.
//  - rotation DEG: the image axes turned about the optical axis (make_synth_camera's roll + DEG; DEG > 0
//    turns the columns' ground direction from east towards south: at 90 the columns run south, the rows
//    west), as from an orbit of another azimuth.
// The last two are geometric: the cameras change, and everything computed from them follows (the scene
// square, the block layout, the terrain grid, the truth tracks, truth.cameras, the RPCs).
#pragma once

#include "tpkit/synth/synth_scene.hpp"

namespace tpkit {

// True when p sets a sensor family (blur, resolution ratio or rotation) for views 2..N.
bool synth_has_sensor(const SynthParams& p);

// Half-width in pixels of the blur kernel of sigma (> 0): ceil(3 sigma).
int synth_blur_radius(double sigma);

}  // namespace tpkit
