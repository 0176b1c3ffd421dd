// Cameras of the synthetic three-line satellite (tp-synth): one 3x4 pixel camera per view, affine
// (parallel projection) or pinhole. Ground frame: X east, Y north, Z up (m); pixels x = column (east),
// y = row (south, the along-track direction of a satellite flying south), origin at the centre of the
// top-left pixel.
#pragma once
#include <Eigen/Core>

namespace tpkit {

struct SynthCamera {
  bool affine = true;
  Eigen::Matrix<double, 3, 4> P = Eigen::Matrix<double, 3, 4>::Zero();  // x ~ P [X Y Z 1]^T (pixels)
  double metres_per_pixel = 1;  // pixel size in the image plane at the scene centre's range (m)

  // Ground (m) -> pixel.
  Eigen::Vector2d project(const Eigen::Vector3d& X) const;
  // Viewing ray of pixel (x, y): unit direction d towards the ground (d.z < 0) and a point o on the ray:
  // affine: the point at height z_top; pinhole: the camera centre.
  void ray(double x, double y, double z_top, Eigen::Vector3d& o, Eigen::Vector3d& d) const;
  // Caches what ray() needs; call after setting P.
  void prepare();

 private:
  Eigen::Matrix3d inv_ = Eigen::Matrix3d::Identity();  // pinhole: M^-1; affine: top-left 2x2 inverse
  Eigen::Vector3d dir_ = -Eigen::Vector3d::UnitZ();     // affine: ray direction
  Eigen::Vector3d centre_ = Eigen::Vector3d::Zero();    // pinhole: camera centre
};

// Camera looking at ground point `centre` from the direction (tan(cross), tan(along), 1) (towards the
// satellite; along > 0: satellite north of the point, i.e. a forward view of a south-bound satellite;
// cross > 0: satellite east), rolled by `roll` about its optical axis (radians), at altitude `altitude` (m)
// with focal length `focal` (pixels); `centre` projects to pixel ((size-1)/2, (size-1)/2). An affine camera is
// the parallel projection with the same orientation and the pixel size of the pinhole at the centre's range.
// Inline: the renderer takes one ray a node.
inline void SynthCamera::ray(double x, double y, double z_top, Eigen::Vector3d& o, Eigen::Vector3d& d) const {
  if (affine) {
    // Origin: the ray's point at height z_top.
    const Eigen::Vector2d rhs(x - P(0, 3) - P(0, 2) * z_top, y - P(1, 3) - P(1, 2) * z_top);
    const Eigen::Vector2d XY = inv_.topLeftCorner<2, 2>() * rhs;
    o = Eigen::Vector3d(XY.x(), XY.y(), z_top);
    d = dir_;
  } else {
    o = centre_;
    d = (inv_ * Eigen::Vector3d(x, y, 1)).normalized();
    if (d.z() > 0) d = -d;
  }
}

SynthCamera make_synth_camera(bool affine, double along, double cross, double roll, double altitude, double focal,
                              const Eigen::Vector3d& centre, long size);

}  // namespace tpkit
