// Rendering of tp-synth views (synth_render.cpp): the pieces the fast renderer SynthScene::render_rows is
// made of, and the exact per-sample reference renderer it is measured against (bench_synth --agreement,
// unit tests).
//
// Pixel response: the mean radiance over n x n samples at offsets (k + 0.5) / n - 0.5 pixel from the pixel
// centre (n = SynthParams::supersample). The reference evaluates every sample on its exact first ray-terrain
// intersection; render_rows evaluates the radiance on a node lattice of step 1 / m pixel (m = ceil(n / 2))
// and takes each sample from the Catmull-Rom interpolation of the nodes, which makes the pixel a fixed
// separable filter of the nodes (SynthNodeFilter).
#pragma once
#include <cstdint>
#include <vector>

#include "tpkit/synth/synth_scene.hpp"

namespace tpkit {

// Pixel (x, y) = sum over i, j in [-r, r] of w[i + r] w[j + r] node(m x + i, m y + j), node (I, J) being the
// radiance at image position (I / m, J / m) (pixels).
struct SynthNodeFilter {
  int m = 1, r = 0;
  std::vector<double> w;  // 2 r + 1 weights, summing to 1
};
SynthNodeFilter synth_node_filter(int supersample);
// The filter of scenes with structures (SynthScene::has_structures): m = n nodes a pixel, node I at image
// position (I + 0.5) / n - 0.5 (the samples themselves), pixel x the mean of nodes n x .. n x + n - 1
// (weights 0 for the taps -r..-1 of r = n - 1): the box response, no interpolation across discontinuities.
SynthNodeFilter synth_box_node_filter(int supersample);

// The 12-bit DN of pixel (x, y) of `view` whose mean radiance is `radiance`: gain, offset, the seeded noise
// of that pixel, the conditions' tone curve and nodata band (synth_conditions.hpp), rounded and clamped.
double synth_finish_dn(const SynthScene& scene, int view, long x, long y, double radiance);

// Rows y0 .. y0 + rows - 1 of `view` as render_rows writes them, but every one of the n x n samples of
// a pixel on its exact ray-terrain intersection (SynthScene::ground_point): slow (about 16 exact casts per
// pixel at n = 4), the truth the fast renderer is compared with.
void synth_reference_rows(const SynthScene& scene, int view, long y0, long rows, uint16_t* out);

}  // namespace tpkit
