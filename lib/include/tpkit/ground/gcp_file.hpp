// Ground control points (GCPs) and check points: one ground position each, known with a sigma, and its
// measurements in one or more images. Two file forms, told apart by the first line:
//
//  - ASP's .gcp (bundle_adjust): per line `id lat lon height sigma_x sigma_y sigma_z` and then, per
//    image it is measured in, `image_name col row sigma_col sigma_row`, separated by spaces or commas.
//    Degrees, metres above the WGS 84 ellipsoid (ASP's default datum; heights above another datum are not
//    converted), pixel sigmas in pixels. The ground sigmas are ASP's default reading: metres along ECEF
//    x, y, z; their diagonal covariance is rotated to east, north, up at the point and its diagonal kept
//    (exact when the three are equal; files written for bundle_adjust --use-lon-lat-height-gcp-error
//    are read the same way). ASP's pixel (col, row) is
//    read as tpkit's (x, y) unchanged: both put (0, 0) at the centre of the top-left pixel (Vision
//    Workbench pixel indices). Every point of an ASP file is a control point (ASP has no check points);
//    `#` lines are comments (ASP's `# WKT:` line included: the WKT is not read, WGS 84 is assumed).
//  - tpkit's `# tpkit gcp 1` (tpkit-formats(5)): images named by `# imageK: PATH W H` header lines, one
//    record per measurement: id role lon lat h sigma_e sigma_n sigma_u image x y sigma_px (role 0 control,
//    1 check; image = K of the header line, x y in tpkit pixels), the point's columns repeated on each of
//    its records (they must agree); a point with no measurement is one record with image 0 and x y nan.
//
// Conventions are converted here only: a Gcp is lon, lat (degrees), h (m above the WGS 84 ellipsoid),
// sigmas east, north, up in metres, measurements in tpkit pixels. InputError (file:line) for a malformed
// line, a sigma that is not positive, a latitude out of range, a point id given twice with other values,
// an id that is not an integer or beyond 2^53 (ids are kept as numbers, which a double holds exactly up
// to there). A UTF-8 byte order mark at the start of a file is skipped; the path '-' is standard input.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

namespace tpkit {

enum class GcpRole { control = 0, check = 1 };

struct GcpMeasurement {
  std::string image;       // as written in the file (matched to the images by the caller)
  Eigen::Vector2d xy;      // tpkit pixels: x = column, y = row, (0, 0) centre of the top-left pixel
  double sigma_px = 1;     // each coordinate
  long line = 0;           // in source
};

struct Gcp {
  long long id = 0;
  GcpRole role = GcpRole::control;
  Eigen::Vector3d llh = Eigen::Vector3d::Zero();        // lon, lat (deg), h (m above the ellipsoid)
  Eigen::Vector3d sigma_enu = Eigen::Vector3d::Ones();  // m: east, north, up
  std::vector<GcpMeasurement> measurements;
  std::string source;
  long line = 0;  // first line of the point
};

// Reads either form (see above) by its first line: `# tpkit gcp` is tpkit's, anything else ASP's.
std::vector<Gcp> read_gcp_file(const std::string& path);
// The points of several files, in order. InputError for a file given twice (the same path, '-' twice, or
// the same file by another name) and for an id in two files: each would count its points twice.
std::vector<Gcp> read_gcp_files(const std::vector<std::string>& paths);
// The same from text (tests; `source` names it in messages).
std::vector<Gcp> parse_asp_gcp(const std::string& text, const std::string& source);
std::vector<Gcp> parse_tpkit_gcp(const std::string& text, const std::string& source);

// Writes tpkit's form (images numbered in order of first use).
std::string format_tpkit_gcp(const std::vector<Gcp>& gcps);

}  // namespace tpkit
