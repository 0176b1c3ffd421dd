// Buildings and trees standing on the terrain of a tp-synth scene (--buildings, --trees, --scene buildings):
// a digital surface model with discontinuities, so that the truth includes occlusion (a ground point
// hidden from a view by a wall or a crown is not visible there) and the map between two views is not
// affine inside a matching window.
//
// Conventions: ground frame X east, Y north, Z up (m), as synth_scene.hpp. The structures stand on lots:
// squares of side kLot metres on a grid rotated by a seeded angle (the lot frame: u, v along the grid,
// metres). Every object lies strictly inside its lot, so a ray meets the objects of the lots it crosses in
// the order it crosses them (a 2-D grid traversal, the first lot with a hit gives the first hit).
//  - building: a box whose walls are vertical and parallel to the lot axes, inset >= 2 m from the lot's
//    edges (streets between), flat roof at (highest terrain under the footprint) + 6..36 m; its walls go
//    down below the lowest terrain (the terrain hides what is under it);
//  - tree: a crown of 3 or 4 ellipsoid lobes (a main one 2..4.5 m across-radius and smaller ones around
//    it: a rough, bumpy canopy) on a 2..5 m trunk that is not modelled (thin).
// A structure is an exact analytic surface: intersections are closed-form (slabs, quadrics), exact to
// rounding. Lots of a building and lots of trees are drawn independently per lot (seeded).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace tpkit {

class SynthTerrain;

// What a ray meets: kind (1 roof, 2 wall, 3 tree crown; 0 means the terrain in SynthSurface), its
// ray parameter t, the unit outward normal, and the index of the building or tree lobe.
struct SynthStructureHit {
  double t = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  int kind = 0;
  int id = -1;
};

class SynthStructures {
 public:
  static constexpr double kLot = 30;  // lot side (m)
  enum Kind { kTerrain = 0, kRoof = 1, kWall = 2, kTree = 3 };
  SynthStructures() = default;  // none: intersect() never hits, top() is -inf
  // seed: RNG seed; buildings, trees: fractions 0..1 of the lots that hold a building, resp. (of the rest)
  // trees; [x0, x1] x [y0, y1]: ground area to fill (m); terrain: the ground they stand on.
  SynthStructures(uint64_t seed, double buildings, double trees, double x0, double y0, double x1, double y1,
                  const SynthTerrain& terrain);
  bool empty() const { return buildings_.empty() && lobes_.empty(); }
  long buildings() const { return static_cast<long>(buildings_.size()); }
  long trees() const { return trees_; }
  double zmax() const { return zmax_; }  // highest roof or crown (m); -inf when empty
  // First hit of o + t d with t in [tmin, tmax] (d: any unit direction): into *hit; false when none. Only
  // surfaces the ray enters count (a ray leaving a roof or wall it starts on does not hit it).
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmin, double tmax, SynthStructureHit* hit) const;
  // Height of the highest structure surface above (X, Y) (m) and its gradient (dZ/dX, dZ/dY): a roof or
  // the upper side of a crown; -inf where there is none.
  double top(double X, double Y, Eigen::Vector2d* grad = nullptr) const;
  // Albedo in [0.02, 0.98] of a structure's surface point X (ground frame) of the given kind and id: roofs
  // (per-building grey with fine texture), walls (window rows every 3 m), crowns (leaf texture).
  // Wavelengths >= 2 gsd, edges smoothsteps of width >= gsd.
  double albedo(int kind, int id, const Eigen::Vector3d& X, double gsd) const;

 private:
  struct Building {
    double u0, u1, v0, v1, zr;  // footprint in the lot frame (m), roof height (m)
    double roof, wall;          // base albedos
    uint64_t seed;
  };
  struct Lobe {
    double cu, cv, cz, rh, rz;  // centre (lot frame u, v; Z), horizontal and vertical radii (m)
    uint64_t seed;
  };
  struct Lot {
    int building = -1;
    int lobe0 = 0, lobe1 = 0;  // lobes_[lobe0 .. lobe1)
  };
  bool lot_hit(const Lot& lot, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmin, double tmax,
               SynthStructureHit* hit) const;  // o, d in the lot frame
  Eigen::Vector3d to_lot(const Eigen::Vector3d& X) const;
  Eigen::Vector3d dir_to_lot(const Eigen::Vector3d& d) const;
  Eigen::Vector3d dir_to_ground(const Eigen::Vector3d& d) const;
  double ca_ = 1, sa_ = 0, ox_ = 0, oy_ = 0;  // lot frame: u = ca (X - ox) + sa (Y - oy), v = -sa (X - ox) + ca (Y - oy)
  long i0_ = 0, j0_ = 0, ni_ = 0, nj_ = 0;     // lots (i, j): u in [i kLot, (i + 1) kLot), likewise v
  std::vector<Lot> lots_;
  std::vector<Building> buildings_;
  std::vector<Lobe> lobes_;
  long trees_ = 0;
  double zbase_ = 0, zmax_ = -1e300;  // lowest wall bottom, highest top (m)
};

}  // namespace tpkit
