// A synthetic satellite triplet, or a block of views from several acquisitions, with exact ground truth
// (tp-synth, man/tp-synth.1).
//
// Local ground frame: X east, Y north, Z up, metres. The scene is the ground square [0, S] x [0, S]
// (S = scene_size()), over which the terrain height spans exactly `relief` metres, centred on Z = 0.
// The terrain and the ground texture are continuous functions of (X, Y) defined everywhere, so every
// pixel of every view sees terrain.
// Views: 0 = forward (satellite north of the scene, about +22 deg along-track), 1 = nadir, 2 = backward
// (about -22 deg); files view1.tif .. view3.tif. The satellite flies south (-Y): image rows (y) increase
// along-track (southward), columns (x) increase eastward. Pixels: x = column, y = row, (0, 0) the centre
// of the top-left pixel. The nadir view has ground sampling distance `gsd` at the scene centre.
// Views 2..N may have another sensor (SynthParams::resolution_ratio, rotation; synth_sensor.hpp): their
// focal length divided by the ratio, their image axes turned about the optical axis; the scene square and
// the block layout below are then computed from those cameras.
//
// Blocks (views != 3 or dates != 1): `dates` acquisitions of k = views / dates views each; view v (0-based)
// is view i = v % k of date d = v / k. Along-track angles within a date run evenly from +22 (forward) to -22
// deg (backward) (k = 1: nadir), each give or take 0.5 deg; each date has its own cross-track angle (seeded,
// 3..12 deg, east for even d, west for odd d; or --cross-track) and roll. Each view looks at its own window
// centre: the windows form a k x dates grid, view i of a date stepping south (along track), dates stepping
// east (adjacent orbits); each step makes the two footprints' extents on that axis overlap by a seeded
// fraction f of the smaller one (one f per gap, shared by every date resp. view index), f in [0.58, 0.68]
// along track and [0.45, 0.6] across, plus a seeded jitter of +-2% of the footprint side on each axis. The scene square is then the square about all
// footprints, and every view sees a different part of it. The focal length is altitude / gsd (a vertical
// view has ground sampling distance gsd).
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
struct SynthCamera;

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
  // single-pass tri-stereo acquisition. Three values: views 1, 2, 3. Blocks: one value (every view), one
  // per date, or one per view.
  std::vector<double> cross_track;
  int views = 3;   // views in all (2..kMaxSynthViews); 3 with dates = 1 is the tri-stereo above
  int dates = 0;   // acquisitions; 0: views / 3 (views must then be a multiple of 3)
  // Conditions (synth_conditions.hpp), radiometric only: the geometry, and so the truth, is unchanged.
  // All 0 (the default) leaves the scene as it was, byte for byte; scene.params names only those set.
  double date2 = 0;   // views 2..N a second date: strength 0..1 of tone, seasonal, texture and sun changes
  double clouds = 0;  // views 2..N: about this fraction of the ground under clouds (0..0.8), with shadows
  double water = 0;   // every view: about this fraction of the ground under featureless water (0..0.8)
  double nodata = 0;  // views 2..N: this fraction of the columns (from the left) is 0 = nodata (0..0.8)
  // Sensor of views 2..N (synth_sensor.hpp). Defaults leave the scene as it was, byte for byte, and
  // scene.params names only those set. blur is radiometric (the truth is unchanged); resolution_ratio and
  // rotation are geometric: the cameras change, and the truth (tracks, cameras, RPCs) follows them.
  double blur = 0;              // Gaussian PSF sigma, pixels of the view (0: none; up to 5)
  double resolution_ratio = 1;  // focal length divided by R: R times the ground sampling distance (1..4)
  double rotation = 0;          // rotated about the optical axis, degrees (-180..180)
  // Structures (synth_structures.hpp): fractions 0..1 of the 30 m lots that hold a building, resp. (of the
  // others) trees. Geometric: the surface, and so the truth (tracks, visibility, truth.dem.tif), includes them;
  // each date's sun casts their shadows. 0 (the default) leaves the scene as it was, byte for byte, and
  // scene.params names them only when set. tp-synth --scene buildings: 0.45 and 0.35.
  double buildings = 0;
  double trees = 0;
};
// tp-synth --scene NAME: "default" (changes nothing) or "buildings" (buildings 0.45, trees 0.35); UsageError
// for another name. The tool applies it before the options that set these fields one by one.
void apply_scene_preset(const std::string& name, SynthParams& p);
constexpr int kMaxSynthViews = 96;
constexpr int kMaxSynthViewsPerDate = 5;

// The number of dates of p (p.dates, or p.views / 3 when 0) and the views per date.
int synth_dates(const SynthParams& p);
inline int synth_views_per_date(const SynthParams& p) { return p.views / synth_dates(p); }
// True for a block (anything but the single-date tri-stereo).
inline bool synth_is_block(const SynthParams& p) { return !(p.views == 3 && synth_dates(p) == 1); }

// "DEG[,DEG...]" (each finite, |DEG| <= 30) -> SynthParams::cross_track; UsageError otherwise (the count
// is checked by check_params).
std::vector<double> parse_cross_track(const std::string&);

// Throws UsageError naming the bad parameter (size < 16, relief < 0, gsd <= 0, unknown camera, ...).
void check_params(const SynthParams&);
void save_params(const std::string& path, const SynthParams&);   // DIR/scene.params, key = value text
SynthParams load_params(const std::string& path);                 // rejects unknown keys (file:line)

class SynthTerrain;   // synth_terrain.hpp
class SynthTexture;   // synth_texture.hpp
struct SynthCamera;   // synth_camera.hpp
class SynthStructures; // synth_structures.hpp

// What a viewing ray meets first: the point X (ground frame, m), the unit outward normal, the kind
// (SynthStructures::Kind: 0 terrain, 1 roof, 2 wall, 3 tree crown) and the building or lobe index (-1: terrain).
struct SynthSurface {
  Eigen::Vector3d X = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  int kind = 0;
  int id = -1;
};

class SynthScene {
 public:
  explicit SynthScene(const SynthParams&);                         // deterministic for params
  static SynthScene load(const std::string& dir);                  // from DIR/scene.params
  SynthScene(SynthScene&&) noexcept;
  SynthScene& operator=(SynthScene&&) noexcept;
  ~SynthScene();

  const SynthParams& params() const;  // dates resolved (synth_dates)
  static constexpr int kViews = 3;  // views of the tri-stereo (view 0 = forward, 1 = nadir, 2 = backward)
  int views() const;                // views of this scene (files view1.tif .. viewN.tif)
  bool is_block() const;
  // Date (0-based) and index within its date (0-based) of `view`; along-, cross-track angles and roll (deg).
  int date_of(int view) const;
  int index_in_date(int view) const;
  Eigen::Vector3d view_angles(int view) const;
  // Where view's image lies on the ground plane Z: the ground points of its image corners (-0.5, -0.5),
  // (n - 0.5, -0.5), (n - 0.5, n - 0.5), (-0.5, n - 0.5) (m, counter-clockwise or clockwise in order).
  std::array<Eigen::Vector2d, 4> footprint(int view, double Z = 0) const;
  // Surface height Z (m) at ground X, Y (m): the terrain, or the roof or crown above it (a digital surface
  // model; the terrain alone without structures).
  double height(double X, double Y) const;
  Eigen::Vector2d project(int view, const Eigen::Vector3d& X) const;// ground (m) -> pixel (x col, y row)
  // First intersection of the viewing ray through pixel (x, y) of `view` with the surface (terrain, roofs,
  // walls, crowns); nothing if it misses.
  std::optional<Eigen::Vector3d> ground_point(int view, double x, double y) const;
  // The same with what the ray meets there (normal, kind).
  std::optional<SynthSurface> surface(int view, double x, double y) const;
  // True when X projects inside `view` and is not hidden by the terrain or a structure along that view's ray.
  bool visible(int view, const Eigen::Vector3d& X) const;
  // 3x4 projection matrix with x ~ P [X Y Z 1]^T in pixels; exact for both camera kinds (affine: last row
  // (0,0,0,1)); truth.cameras holds these.
  Eigen::Matrix<double, 3, 4> camera(int view) const;

  // --- additions ---
  // Side S of the scene square [0, S]^2 (m): chosen so that the scene at every height of the relief
  // projects inside all three views with a margin.
  double scene_size() const;
  // Gradient (dZ/dX, dZ/dY) of height() at ground X, Y (m).
  Eigen::Vector2d height_gradient(double X, double Y) const;
  // Ground albedo in [0, 1] at X, Y (m): band-limited, continuous.
  double albedo(double X, double Y) const;
  // Albedo times slope shading (ambient + Lambert, sun fixed in the scene), in [0, 1]; view independent.
  double radiance(double X, double Y) const;
  // The same with the terrain gradient at (X, Y) already known.
  double radiance(double X, double Y, const Eigen::Vector2d& grad) const;
  // radiance(X[i], Y[i], (gx[i], gy[i])) into out[i], i < n: the same values, faster for many points.
  void radiance_n(long n, const double* X, const double* Y, const double* gx, const double* gy, double* out) const;
  // Viewing ray of pixel (x, y) of `view`: a point on it above the terrain and the unit direction
  // towards the ground (ground frame, m).
  void ray(int view, double x, double y, Eigen::Vector3d& origin, Eigen::Vector3d& dir) const;
  // Buildings and trees (empty without SynthParams::buildings, trees).
  const SynthStructures& structures() const;
  bool has_structures() const;
  // Unit vector towards the sun of `view`'s date (ground frame): the scene's sun for date 1; the second
  // date's (synth_conditions.hpp) for views 2..N with --second-date; a seeded sun per later date of a block.
  // Scenes with structures shade and cast shadows with it; the others keep the scene's sun (as before).
  Eigen::Vector3d sun(int view) const;
  // True when a structure stands between X (with outward normal n) and `view`'s sun: X in a cast shadow.
  bool in_shadow(int view, const Eigen::Vector3d& X, const Eigen::Vector3d& n) const;
  // Radiance of a surface point seen in `view` (scenes with structures): albedo (the ground's texture and
  // conditions, or the structure's) times ambient 0.3 + 0.7 cos(sun, normal), the direct part 0 in a
  // cast shadow.
  double surface_radiance(int view, const SynthSurface&) const;
  // Per-view radiometry: DN = gain * radiance + offset + noise, clamped to [0, 4095].
  double gain(int view) const;
  double offset(int view) const;
  // Renders rows y0 .. y0 + rows - 1 of `view` (width = size) into out (row-major uint16, 12-bit).
  // Noise is a function of (seed, view, pixel), so the result does not depend on strip or thread.
  // The view's blur (SynthParams::blur) is not applied here: sensor_rows does.
  void render_rows(int view, long y0, long rows, uint16_t* out) const;
  // The same rows as the view's sensor records them (synth_sensor.hpp): render_rows where the view has no
  // blur; else the sharp, noise-free rendering blurred by the PSF, then the noise and the nodata band.
  // Independent of strip and thread as render_rows is. write_synth_scene writes these.
  void sensor_rows(int view, long y0, long rows, uint16_t* out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  const SynthTerrain& terrain_() const;
  // The camera of `view` and the height of its ray origins (ray() is camera_(view).ray(x, y, z_top_(), ..)).
  const SynthCamera& camera_(int view) const;
  double z_top_() const;
  // With SynthParams::blur > 0: this scene seen by ideal sensors (no blur, no noise, no nodata band), the
  // rendering sensor_rows blurs; nullptr otherwise.
  const SynthScene* sharp_() const;
  explicit SynthScene(std::unique_ptr<Impl>);
};

// Truth tracks: `points` ground points on the terrain in the scene square, stratified over the scene
// (deterministic for the seed): for the tri-stereo each visible in all three views; for a block each
// visible (inside the image and not hidden by terrain) in 2 views or more. Rows of xy: x1 y1 .. xN yN
// (pixels; NaN NaN where the view does not see the point); rows of ground: X Y Z (m).
struct SynthTruth {
  Eigen::MatrixXd xy;      // n x 2N
  Eigen::MatrixX3d ground; // n x 3
};
SynthTruth synth_truth_points(const SynthScene&, long points);

// Footprint overlap of views a and b: area of the intersection of their footprints on Z = 0 over the area of
// the smaller one (0..1).
double synth_footprint_overlap(const SynthScene&, int a, int b);
// Neighbouring views of the block layout (a < b, 0-based): consecutive views of one date, and the same view
// index of consecutive dates. The tri-stereo: every pair.
std::vector<std::pair<int, int>> synth_neighbours(const SynthScene&);

// Seeded random RPC biases (synth_rpc.hpp convention) for every view of the scene: each component at every
// pixel of the view at most `px` pixels: shift uniform in +-px/2, and the drift (per row) and affine (per
// column) terms each uniform so that they change by at most +-px/4 across the image. Deterministic for the
// scene's seed and the view.
ImageBias synth_random_bias(const SynthScene&, int view, double px);

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
// Writes view1..N.tif, truth.tracks, truth.cameras, truth.trifocal (three views, affine only) and
// scene.params into dir (created if needed), each atomically; with rpc also view1..N_rpc.txt, truth.bias and
// truth.dem.tif. Files view<K>.tif / view<K>_rpc.txt of an older scene with more views are removed.
void write_synth_scene(const SynthScene&, const std::string& dir, const SynthWriteOptions& = {});

}  // namespace tpkit
