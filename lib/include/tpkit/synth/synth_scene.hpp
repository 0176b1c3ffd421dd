// A synthetic satellite triplet with exact ground truth (tp-synth, man/tp-synth.1).
//
// Local ground frame: X east, Y north, Z up, metres. The scene is the ground square [0, S] x [0, S]
// (S = scene_size()), over which the terrain height spans exactly `relief` metres, centred on Z = 0.
// The terrain and the ground texture are continuous functions of (X, Y) defined everywhere, so every
// pixel of every view sees terrain.
// Views: 0 = forward (satellite north of the scene, about +22 deg along-track), 1 = nadir, 2 = backward
// (about -22 deg); files view1.tif .. view3.tif. The satellite flies south (-Y): image rows (y) increase
// along-track (southward), columns (x) increase eastward. Pixels: x = column, y = row, (0, 0) the centre
// of the top-left pixel. The nadir view has ground sampling distance `gsd` at the scene centre.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tpkit/synth/synth_rpc.hpp"

namespace tpkit {

struct SynthParams {
  uint64_t seed = 1;
  long size = 1024;              // width = height of each view, pixels
  double relief = 150;           // terrain relief (max - min height), metres
  double gsd = 0.5;              // ground sampling distance of the nadir view, metres/pixel
  std::string camera = "affine"; // "affine" or "perspective"
  long points = 2000;            // truth tracks to write
  double noise = 2.0;            // sensor noise sigma, DN (12-bit range)
  long supersample = 4;          // rendering: n x n samples per pixel (box pixel response)
  // Cross-track angles of the views, degrees (satellite east of the scene > 0). Empty: seeded, one
  // angle of 2..3 deg for all views give or take 0.3 deg per view (the default). One value: every view
  // exactly that angle, so the three viewing directions (tan c, tan a_v, 1) lie in one plane, as in a
  // single-pass tri-stereo acquisition. Three values: views 1, 2, 3.
  std::vector<double> cross_track;
};

// "DEG" or "DEG,DEG,DEG" (each finite, |DEG| <= 30) -> SynthParams::cross_track; UsageError otherwise.
std::vector<double> parse_cross_track(const std::string&);

// Throws UsageError naming the bad parameter (size < 16, relief < 0, gsd <= 0, unknown camera, ...).
void check_params(const SynthParams&);
void save_params(const std::string& path, const SynthParams&);   // DIR/scene.params, key = value text
SynthParams load_params(const std::string& path);                 // rejects unknown keys (file:line)

class SynthTerrain;   // synth_terrain.hpp
class SynthTexture;   // synth_texture.hpp
struct SynthCamera;   // synth_camera.hpp

class SynthScene {
 public:
  explicit SynthScene(const SynthParams&);                         // deterministic for params
  static SynthScene load(const std::string& dir);                  // from DIR/scene.params
  SynthScene(SynthScene&&) noexcept;
  SynthScene& operator=(SynthScene&&) noexcept;
  ~SynthScene();

  const SynthParams& params() const;
  static constexpr int kViews = 3;  // view 0 = forward, 1 = nadir, 2 = backward (files view1..view3.tif)
  double height(double X, double Y) const;                          // terrain height Z (m) at ground X, Y (m)
  Eigen::Vector2d project(int view, const Eigen::Vector3d& X) const;// ground (m) -> pixel (x col, y row)
  // First intersection of the viewing ray through pixel (x, y) of `view` with the terrain; nothing if it misses.
  std::optional<Eigen::Vector3d> ground_point(int view, double x, double y) const;
  // True when X projects inside `view` and is not hidden by terrain along that view's ray.
  bool visible(int view, const Eigen::Vector3d& X) const;
  // 3x4 projection matrix with x ~ P [X Y Z 1]^T in pixels; exact for both camera kinds (affine: last row
  // (0,0,0,1)); truth.cameras holds these.
  Eigen::Matrix<double, 3, 4> camera(int view) const;

  // --- additions ---
  // Side S of the scene square [0, S]^2 (m): chosen so that the scene at every height of the relief
  // projects inside all three views with a margin.
  double scene_size() const;
  // Terrain gradient (dZ/dX, dZ/dY) at ground X, Y (m).
  Eigen::Vector2d height_gradient(double X, double Y) const;
  // Ground albedo in [0, 1] at X, Y (m): band-limited, continuous.
  double albedo(double X, double Y) const;
  // Albedo times slope shading (ambient + Lambert, sun fixed in the scene), in [0, 1]; view independent.
  double radiance(double X, double Y) const;
  // The same with the terrain gradient at (X, Y) already known.
  double radiance(double X, double Y, const Eigen::Vector2d& grad) const;
  // Viewing ray of pixel (x, y) of `view`: a point on it above the terrain and the unit direction
  // towards the ground (ground frame, m).
  void ray(int view, double x, double y, Eigen::Vector3d& origin, Eigen::Vector3d& dir) const;
  // Per-view radiometry: DN = gain * radiance + offset + noise, clamped to [0, 4095].
  double gain(int view) const;
  double offset(int view) const;
  // Renders rows y0 .. y0 + rows - 1 of `view` (width = size) into out (row-major uint16, 12-bit).
  // Noise is a function of (seed, view, pixel), so the result does not depend on strip or thread.
  void render_rows(int view, long y0, long rows, uint16_t* out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  const SynthTerrain& terrain_() const;
  explicit SynthScene(std::unique_ptr<Impl>);
};

// Truth tracks: `points` ground points in the scene square visible in all three views, stratified over
// the scene (deterministic for the seed). Rows of xy: x1 y1 x2 y2 x3 y3 (pixels); rows of ground: X Y Z (m).
struct SynthTruth {
  Eigen::MatrixXd xy;      // n x 6
  Eigen::MatrixX3d ground; // n x 3
};
SynthTruth synth_truth_points(const SynthScene&, long points);

// H&Z trifocal tensor T[i](j, k) = T_i^{jk} of the three pixel cameras P1, P2, P3 (views 0, 1, 2):
// camera 1 is made canonical by H with P1 H = [I | 0], then T_i = a_i b_4^T - a_4 b_i^T with
// P2 H = [a_1 .. a_4], P3 H = [b_1 .. b_4]. Not normalized.
std::array<Eigen::Matrix3d, 3> trifocal_from_cameras(const Eigen::Matrix<double, 3, 4>& P1,
                                                     const Eigen::Matrix<double, 3, 4>& P2,
                                                     const Eigen::Matrix<double, 3, 4>& P3);

struct SynthWriteOptions {
  int threads = 0;        // 0: all cores
  long strip_rows = 32;   // rows per rendered strip
  // RPCs (synth_rpc.hpp): each view's RPC00B (biased by rpc_bias[view] where given) goes into the view's
  // tag 50844 and viewN_rpc.txt; truth.tracks gets lon lat h columns, truth.bias the injected biases.
  bool rpc = true;
  SynthGeoOrigin origin;
  std::map<int, ImageBias> rpc_bias;  // view (0-based) -> bias
};
// Writes view1..3.tif, truth.tracks, truth.cameras, truth.trifocal (affine only) and scene.params into
// dir (created if needed), each atomically; with rpc also view1..3_rpc.txt and truth.bias.
void write_synth_scene(const SynthScene&, const std::string& dir, const SynthWriteOptions& = {});

}  // namespace tpkit
