// Hidden ground in an ortho made on a surface model ("true ortho"): a ground point of the grid whose line of
// sight to the sensor passes below the surface on its way up (behind a building, a tree or a ridge, as the
// view sees it) shows in the image what hides it, not itself; an ortho that keeps it repeats the roof's edge
// over the ground behind it, a copy that lies in a different place for every view (away from the sensor),
// so that two dates never overlay there however good their models are.
//
// Conventions: heights on the ortho grid's pixels (ortho_grid.hpp; c = column, r = row), metres above the
// ellipsoid, row-major, NaN where unknown. The line of sight is the grid displacement (dc, dr), in grid pixels,
// of the ground point seen at the same image pixel one metre higher: along it, towards the sensor, the ray
// rises 1 m per (dc, dr). Over the few hundred metres of a tile a satellite's lines of sight are parallel
// (the sensor is hundreds of kilometres away: they turn by less than 0.05 degree across a kilometre).
#pragma once
#include <vector>

#include "tpkit/ortho/ortho_grid.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

struct LineOfSight {
  double dc = 0, dr = 0;  // grid pixels per metre of height, towards the sensor
};

// The line of sight of `model` at grid pixel (c, r) and height h (metres above the ellipsoid), from the
// model's derivatives there; NaN components where the model cannot be differentiated (off its domain).
LineOfSight line_of_sight(const RpcModel& model, const OrthoGrid& grid, const GridCrs& crs, double c, double r, double h);

// A window of heights on the grid: `z` (width x height, row-major) holds the heights of grid pixels
// (c0 + i, r0 + j).
struct HeightWindow {
  long c0 = 0, r0 = 0, width = 0, height = 0;
  std::vector<double> z;
};

// Marks the grid pixels of the rectangle (c0, r0, w, h) (inside the window) whose ray towards the sensor
// meets the window's surface (bilinear between its samples) more than `tolerance` metres above the ray,
// searched in steps of half a pixel up to the window's highest point or its edge (a pixel whose occluder lies
// beyond the window is not marked). hidden[(r - r0) * w + (c - c0)] = 1 for a hidden pixel, 0 otherwise
// (also for pixels without a height). Returns the hidden pixels.
long mark_hidden(const HeightWindow& heights, const LineOfSight& los, long c0, long r0, long w, long h, double tolerance,
                 std::vector<char>& hidden);

// Marks (adds to `hidden`, as mark_hidden lays it out) the pixels of the rectangle where the window's surface
// is steeper than `slope_deg` (central differences over two grid pixels of `gsd` metres): walls, which a
// surface model on a grid holds as ramps. Returns the pixels marked that were not already.
long mark_walls(const HeightWindow& heights, double gsd, double slope_deg, long c0, long r0, long w, long h, std::vector<char>& hidden);

// The margin, pixels, around a rectangle that holds every occluder of its pixels: the surface's relief (its
// highest minus its lowest height, metres) along the line of sight, capped at `cap` pixels.
long occluder_margin(const LineOfSight& los, double relief_m, long cap);

}  // namespace tpkit
