// Single points through one RPC model, streamed as PROJ's cct streams them (tp-rpc project / localize):
//   project    input  lon lat h [extra...]   (degrees, metres above the WGS84 ellipsoid)
//              output x y h [extra...]       (pixels: x = column, y = row, (0, 0) the centre of the
//                                             top-left pixel; h passed on)
//   localize   input  x y h [extra...]   -> output lon lat h [extra...]: the ground point of the pixel at
//              height h (RpcModel::localize, residual below 1e-8 px);
//              with a DEM: input x y [extra...] -> lon lat h [extra...], h the DEM's (bilinear) height
//              where the line of sight meets it: f(h) = DEM(localize(x, y, h)) - h sampled at 65 heights
//              over the model's height range, its highest sign change refined by bisection to 1e-4 m.
// Lines that are empty or start with '#' pass through unchanged; the coordinate columns (separated by
// blanks or tabs) are replaced, everything after them is kept byte for byte; one output line per input
// line. Numbers are written in the shortest form that reads back to the same double. Each output line is
// written as its input line is read, so that a filter on a pipe answers as the points come and holds no
// more than a line (as cct). A line with too few columns or a value that is not a finite number is an
// InputError(source:line), thrown after the lines before it were written (a caller that must leave
// nothing behind writes to an atomic output). A point without a solution (a localization that does not
// converge, a pole of the model, a ground point that is none or far outside the model's box:
// RpcModel::outside_domain, a line of sight the DEM does not cover) is written "nan nan nan" with
// its extra columns, and counted.
// With a ground system (GroundConverter: UTM in the zone of the model's centre, or ECEF), the ground
// coordinates read by project and written by localize are in it (easting northing h, X Y Z) instead of
// lon lat h; the pixel side keeps its height above the ellipsoid.
#pragma once
#include <istream>
#include <ostream>
#include <string>

#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

class ReferenceDem;
class GroundConverter;

enum class RpcPointDirection { Project, Localize };

struct RpcPointStats {
  long points = 0;    // lines transformed
  long comments = 0;  // lines passed through
  long outside = 0;   // points outside the model's validity box (RpcModel::outside_validity_box, 10% margin): counted only
  long unsolved = 0;  // points written as nan
  std::string first_unsolved;  // "source:line: reason" of the first of them
};

// The transformed text of `in` (named `source` in messages), written to `out`. `dem` (localize only, may be null): the ground
// (reference_dem.hpp, any CRS and vertical datum) where each line of sight meets it.
void transform_rpc_points(std::istream& in, const std::string& source, std::ostream& out, const RpcModel& model,
                          RpcPointDirection direction, const ReferenceDem* dem, RpcPointStats* stats = nullptr,
                          const GroundConverter* crs = nullptr);

}  // namespace tpkit
