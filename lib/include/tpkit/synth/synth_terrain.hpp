// The terrain height field of the synthetic scene (tp-synth): a uniform bicubic B-spline over a grid of
// control heights. Control heights are a fractal sum of value-noise octaves plus a few large hills and
// valleys, scaled so that the surface spans exactly `relief` metres over the scene square [0, S]^2
// (centred on Z = 0). Ground frame: X east, Y north, Z up, metres.
//
// The B-spline is C2 and, by its convex-hull property, lies inside [min, max] of the 4x4 control heights
// of each cell, and its gradient is bounded by the control differences: ray casting skips cells whose
// bound the ray passes above, and inside a cell samples (ray height - terrain height) at half-cell steps,
// subdividing any step where the slope bound allows a hidden dip below the terrain, then refines the
// first sign change by bracketing: the first intersection, occlusion included, is found for certain.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

namespace tpkit {

class SynthTerrain {
 public:
  SynthTerrain() = default;
  // seed: RNG seed; scene: side S of the scene square (m); relief: max - min height over the scene (m);
  // spacing: control grid spacing (m); [x0, x1] x [y0, y1]: ground area the grid must cover (m).
  SynthTerrain(uint64_t seed, double scene, double relief, double spacing, double x0, double y0, double x1,
               double y1);
  // Height Z (m) at ground X, Y (m). Outside the grid the nearest border value is used (continuous).
  double height(double X, double Y) const;
  // Height and gradient (dZ/dX, dZ/dY).
  double height(double X, double Y, Eigen::Vector2d* grad) const;
  // Bounds of the height everywhere (m).
  double zmin() const { return zmin_; }
  double zmax() const { return zmax_; }
  // First t >= 0 where o + t d meets the terrain (d: any direction with d.z < 0; o: any point). Nothing
  // when the ray leaves the height bounds without meeting it (or d.z >= 0).
  // tol: bracket width (m along the ray) at which the refinement stops.
  std::optional<double> intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tol = 1e-10) const;
  // Newton refinement of the intersection starting from t0; nan if it does not converge quickly (caller
  // falls back to intersect()); a double rather than an optional, which cost a store-forwarding stall at
  // every return. The renderer's ground points between its exact casts (synth_render.cpp).
  // tol: stop when the Newton step is below tol (m along the ray); the error of the result is then of
  // the order of curvature x tol^2. grad (optional): terrain gradient at the last evaluation.
  // patch (optional): the cell polynomial of the caller's last refine(), reused while its Newton steps stay
  // in that cell (consecutive nodes of a rendered row mostly do).
  struct Patch {
    long ku = -1, kv = -1;  // its cell: u in [ku, ku + 1), v in [kv, kv + 1) grid units; -1: none yet
    double c[4][4] = {};    // surface = sum over k, j of c[k][j] s^k r^j (s = u - ku, r = v - kv)
  };
  double refine(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0, double tol = 1e-10,
                Eigen::Vector2d* grad = nullptr, Patch* patch = nullptr) const;
  // refine() of n <= kLanes rays at once, their Newton steps interleaved: the chains are independent, so
  // the CPU overlaps their latencies (the same result per ray as refine()). t[k]: start in, result or nan
  // out (a nan start gives nan); grad[k], patch[k]: as refine()'s, per ray.
  static constexpr int kLanes = 4;
  void refine_lanes(int n, const Eigen::Vector3d* o, const Eigen::Vector3d* d, double* t, double tol, Eigen::Vector2d* grad,
                    Patch* patch) const;

 private:
  double eval(double u, double v, double* du, double* dv) const;  // grid units
  double h_ = 1, gx0_ = 0, gy0_ = 0;
  long nx_ = 0, ny_ = 0;           // control points
  std::vector<float> c_;           // ny x nx control heights
  std::vector<float> cmax_;        // (ny-3) x (nx-3) per-cell upper bound; cell (i, j) spans u in [i+1, i+2)
  std::vector<float> cslope_;      // per-cell bound of |grad h| (m/m), from the control differences
  double zmin_ = 0, zmax_ = 0, slope_max_ = 0;
};

}  // namespace tpkit
