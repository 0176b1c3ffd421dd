// Sensors of views 2..N of tp-synth (synth_sensor.hpp): the blurred rows of SynthScene::sensor_rows.
#include "tpkit/synth/synth_sensor.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tpkit/synth/synth_conditions.hpp"
#include "tpkit/synth/synth_noise.hpp"

namespace tpkit {

bool synth_has_sensor(const SynthParams& p) { return p.blur != 0 || p.resolution_ratio != 1 || p.rotation != 0; }

int synth_blur_radius(double sigma) { return static_cast<int>(std::ceil(3 * sigma)); }

void SynthScene::sensor_rows(int view, long y0, long rows, uint16_t* out) const {
  const SynthParams& p = params();
  const SynthScene* sharp = sharp_();
  if (view == 0 || !sharp) {
    render_rows(view, y0, rows, out);
    return;
  }
  // Stage 1: the sharp, noise-free DN of rows y0 - r .. y0 + rows - 1 + r, rows beyond the image repeating its
  // edge rows, so that every output row sees the same input whatever the strip.
  const long W = p.size;
  const int r = synth_blur_radius(p.blur);
  const long a = std::max(0L, y0 - r), b = std::min(W, y0 + rows + r);
  std::vector<uint16_t> sharp_dn(static_cast<size_t>((b - a) * W));
  sharp->render_rows(view, a, b - a, sharp_dn.data());
  cv::Mat block(static_cast<int>(rows + 2 * r), static_cast<int>(W), CV_64F);
  for (int j = 0; j < block.rows; ++j) {
    const long y = std::clamp(y0 - r + j, 0L, W - 1);
    const uint16_t* src = &sharp_dn[static_cast<size_t>((y - a) * W)];
    double* dst = block.ptr<double>(j);
    for (long x = 0; x < W; ++x) dst[x] = src[x];
  }
  // Stage 2: the PSF (rows of the block beyond the output are only read, so the border mode acts on columns).
  cv::Mat blurred;
  cv::GaussianBlur(block, blurred, cv::Size(2 * r + 1, 2 * r + 1), p.blur, p.blur, cv::BORDER_REPLICATE);
  // Stage 3: noise, nodata band (the twin had none; its tone curve is already applied), 12-bit DN.
  SynthParams band;
  band.size = p.size;
  band.nodata = p.nodata;
  const uint64_t ns_seed = synth::hash(p.seed, 0x5e45, view);
  for (long j = 0; j < rows; ++j) {
    const double* src = blurred.ptr<double>(static_cast<int>(j + r));
    for (long x = 0; x < W; ++x) {
      double dn = src[x];
      if (p.noise > 0) dn += p.noise * synth::normal(synth::hash(ns_seed, y0 + j, x));
      if (synth_has_conditions(p)) dn = synth_condition_dn(band, view, x, dn);  // nodata band; DN >= 1 elsewhere
      out[static_cast<size_t>(j * W + x)] = static_cast<uint16_t>(std::clamp(std::round(dn), 0.0, 4095.0));
    }
  }
}

}  // namespace tpkit
