// The file kinds that tpkit tools exchange (man/tpkit-formats.5), on top of text_table.hpp.
//
//   matches     columns id1 x1 y1 id2 x2 y2 [extra...]       pair of images (image1, image2)
//   tracks      columns track x1 y1 ... xK yK [extra...]     K images (image1..imageK); a view the track
//               is not seen in is "nan nan" (x and y both), every track is seen in 2 views or more;
//               a file holding such views is written as version 2 (version 1 readers refuse it);
//               optional columns sigma1 ... sigmaK: standard deviation of each view's position, px
//   points      columns x y [extra...]                       a point cluster
//   trifocal    three records of nine numbers: record i = T_i (i = 1..3), row j, column k, row-major,
//               Hartley & Zisserman T_i^{jk}; acts on homogeneous pixels (x, y, 1); Frobenius norm 1
//   homography  three records of three numbers: x2 ~ H x1 on homogeneous pixels
//   cameras     "# view N" then three records of four numbers per view (3x4 projection matrix)
//
// Pixels: x = column, y = row, origin at the centre of the top-left pixel. Every reader takes a path
// or "-" (stdin); every save_* writes atomically (atomic_output.hpp), "-" being stdout.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "tpkit/core/text_table.hpp"

namespace tpkit {

// Extra columns beyond the kind's own: kept when read, written back after the kind's columns.
struct ExtraColumns {
  std::vector<std::string> names;
  Eigen::MatrixXd values;  // rows x names.size()
  int find(const std::string& name) const;
};

struct Matches {
  std::string source;
  ImageRef image1, image2;
  Meta meta;
  std::vector<long long> id1, id2;  // keypoint ids in image1 and image2
  Eigen::MatrixXd xy;               // n x 4: x1 y1 x2 y2
  ExtraColumns extra;
  std::vector<long> line;           // source line of each record (empty when built in memory)
  size_t size() const { return static_cast<size_t>(xy.rows()); }
};

struct Tracks {
  std::string source;
  std::vector<ImageRef> images;  // K images; column pair k holds the position in image k+1
  Meta meta;
  std::vector<long long> id;     // track ids
  Eigen::MatrixXd xy;            // n x 2K: x1 y1 x2 y2 ... xK yK
  ExtraColumns extra;
  std::vector<long> line;
  size_t size() const { return static_cast<size_t>(xy.rows()); }
  // Number of images (column pairs); a track is seen in 2 of them or more.
  int views() const { return static_cast<int>(xy.cols() / 2); }
  Eigen::Vector2d point(size_t track, int view) const { return xy.block<1, 2>(track, 2 * view).transpose(); }
  // Whether the track is seen in image view+1 (its x is not NaN).
  bool seen(size_t track, int view) const { return !std::isnan(xy(static_cast<Eigen::Index>(track), 2 * view)); }
  // Images the track is seen in.
  int seen_views(size_t track) const;
  // Whether every track is seen in every image.
  bool complete() const;
};

// The tracks seen in every image (extra columns and source lines kept), for the methods that need all
// views (trifocal-fit, reproj-eval); `left_out`, when not null, receives the number of tracks dropped.
Tracks tracks_seen_in_all_views(const Tracks& t, size_t* left_out = nullptr);
// A tracks file of exactly `views` images, its tracks seen in all of them: a file of another number of
// images, or none of whose tracks is seen in all, is refused (InputError); `left_out` as above.
Tracks read_tracks_seen_in_all_views(const std::string& path, int views, size_t* left_out);

struct Points {
  std::string source;
  std::vector<ImageRef> images;
  Meta meta;
  Eigen::MatrixX2d xy;  // n x 2
  ExtraColumns extra;
  std::vector<long> line;
  size_t size() const { return static_cast<size_t>(xy.rows()); }
};

// T[i](j, k) = T_i^{jk}, i, j, k = 0..2 for the book's 1..3.
struct Trifocal {
  std::string source;
  std::vector<ImageRef> images;
  Meta meta;  // method, counts, ...
  std::array<Eigen::Matrix3d, 3> T;
};

struct Homography {
  std::string source;
  std::vector<ImageRef> images;
  Meta meta;
  Eigen::Matrix3d H;  // x2 ~ H x1
};

struct Cameras {
  std::string source;
  std::vector<ImageRef> images;
  Meta meta;
  std::vector<Eigen::Matrix<double, 3, 4>> P;  // P[v] for view v+1
};

Matches read_matches(const std::string& path);
Tracks read_tracks(const std::string& path);
Points read_points(const std::string& path);
Trifocal read_trifocal(const std::string& path);
Homography read_homography(const std::string& path);
Cameras read_cameras(const std::string& path);

// From an already parsed table (fuzz targets, tests).
Matches matches_from_table(const TextTable& t);
Tracks tracks_from_table(const TextTable& t);
Points points_from_table(const TextTable& t);
Trifocal trifocal_from_table(const TextTable& t);
Homography homography_from_table(const TextTable& t);
Cameras cameras_from_table(const TextTable& t);
// Read options (kind, default columns) of each kind.
ReadOptions matches_read_options();
ReadOptions tracks_read_options();
ReadOptions points_read_options();
ReadOptions trifocal_read_options();
ReadOptions homography_read_options();
ReadOptions cameras_read_options();

void write_matches(std::ostream& os, const Matches& m);
void write_tracks(std::ostream& os, const Tracks& t);
void write_points(std::ostream& os, const Points& p);
// Scales T to Frobenius norm 1 with its largest-magnitude entry positive before writing.
void write_trifocal(std::ostream& os, const Trifocal& t);
void write_homography(std::ostream& os, const Homography& h);
void write_cameras(std::ostream& os, const Cameras& c);

void save_matches(const std::string& path, const Matches& m);
void save_tracks(const std::string& path, const Tracks& t);
void save_points(const std::string& path, const Points& p);
void save_trifocal(const std::string& path, const Trifocal& t);
void save_homography(const std::string& path, const Homography& h);
void save_cameras(const std::string& path, const Cameras& c);

// The trifocal tensor scaled to Frobenius norm 1, sign fixed (largest-magnitude entry positive).
std::array<Eigen::Matrix3d, 3> normalized_trifocal(const std::array<Eigen::Matrix3d, 3>& T);

}  // namespace tpkit
