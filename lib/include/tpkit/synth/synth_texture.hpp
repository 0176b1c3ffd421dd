// Ground albedo of the synthetic scene (tp-synth): an analytic, continuous function of ground (X, Y) in
// metres with structure at several scales, laid out on a block grid rotated by a seeded angle:
//   blocks (240 m): farmland (parcels with distinct albedo, crop-row stripes, dark hedges), urban (lots
//   with gabled building roofs and cast-shadow bands on pavement) or woodland (tree-crown blobs);
//   straight roads along some block-grid lines with dashed centre markings; a slow large-scale albedo
//   modulation and fine-scale noise.
// Every edge is a smoothstep of width max(gsd, 0.3 m) and every periodic or noise pattern has a
// wavelength of at least ~2 gsd, so supersampled rendering is exact to within its sampling.
#pragma once
#include <cstdint>

namespace tpkit {

class SynthTexture {
 public:
  SynthTexture() = default;
  // seed: RNG seed; gsd: finest ground sampling distance it will be rendered at (m/pixel); sun_azimuth:
  // direction towards the sun in the ground frame, radians counter-clockwise from +X (east); sun_elevation:
  // radians above the horizon (building shadows point away from the sun).
  SynthTexture(uint64_t seed, double gsd, double sun_azimuth, double sun_elevation);
  // Albedo in [0.02, 0.98] at ground X, Y (m).
  double albedo(double X, double Y) const;
  // albedo(X[i], Y[i]) into out[i], i < n (the same values): the layout point by point, then the two noises
  // over (X, Y) in a pass of their own, short independent iterations that the CPU overlaps.
  void albedo_n(long n, const double* X, const double* Y, double* out) const;

 private:
  double farmland(int64_t bi, int64_t bj, double lu, double lv, double u, double v) const;
  double urban(int64_t bi, int64_t bj, double lu, double lv, double u, double v) const;
  double woodland(double u, double v) const;
  double layout(double X, double Y) const;  // albedo before its two (X, Y) noises (synth_texture.cpp: modulate)
  uint64_t seed_ = 1;
  uint64_t noise_seed_[5] = {};   // hash(seed_, k) of the value-noise streams k = 20, 30, 31, 50, 51
  double gsd_ = 0.5, ew_ = 0.5;   // ground sampling distance, edge width (m)
  double ca_ = 1, sa_ = 0, ou_ = 0, ov_ = 0;  // layout frame: rotation, offset
  double block_ = 240;
  // Reciprocals of the block size and of the crown and fine-noise wavelengths (max(5, 3 gsd), max(1, 2 gsd)):
  // the texture multiplies where it would divide (a last-bit difference in a noise argument, nothing more)
  double inv_block_ = 1.0 / 240, inv_crown_ = 0.2, inv_fine_ = 1;
  double sun_u_ = 0.5, sun_v_ = 0.5;          // shadow offset direction per metre of building height
};

}  // namespace tpkit
