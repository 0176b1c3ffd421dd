// Deterministic subsets of the records of a tpkit table file (tracks, matches, points): a region filter
// on one view's position, then a random draw of n records by a seed, the rest kept apart as check
// (held-out) records. Used to draw the fit / check point sets of the experiments.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tpkit/core/text_table.hpp"

namespace tpkit {

struct SampleOptions {
  long n = -1;              // records to draw; < 0 keeps all (after the box filter)
  uint64_t seed = 1;
  bool spread = false;      // draw spread over the image: one record per cell of a grid, cells in random order
  // Keep only records whose position in view `box_view` (columns x<view> y<view>, or x y for points)
  // lies in [x0, x1] x [y0, y1] (pixels).
  std::optional<std::array<double, 4>> box;
  int box_view = 1;
};

struct SampleResult {
  std::vector<size_t> drawn;  // record indices, in file order
  std::vector<size_t> rest;   // records inside the box that were not drawn, in file order
};

// Draws from `t`; throws UsageError when n exceeds the records available.
SampleResult sample_records(const TextTable& t, const SampleOptions& opt);

// Writes the header of `t` (kind, images, metadata plus `extra_meta`, columns) and the chosen records.
void write_table_subset(std::ostream& os, const TextTable& t, const std::vector<size_t>& rows, const Meta& extra_meta);

}  // namespace tpkit
