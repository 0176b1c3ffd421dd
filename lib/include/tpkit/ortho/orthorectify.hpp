// Orthorectification through an RPC model: every pixel of the output grid is a ground point (its centre, at
// the surface's height there: a reference DEM's, or a flat height), projected into the image through the
// model (the model's own, fast direction: ground -> image) and resampled there.
//
// Conventions: grid as ortho_grid.hpp (pixel (c, r) at (x0 + (c + 0.5) gsd, y0 - (r + 0.5) gsd)); image pixels
// x = column, y = row, (0, 0) the centre of the top-left pixel (the RPC's own convention, rpc_model.hpp);
// heights above the WGS 84 ellipsoid (a DEM's converted by ReferenceDem from its vertical datum).
// Resampling: bilinear between the 4 pixel centres around (x, y), or bicubic (Keys, a = -0.5: GDAL's "cubic")
// over the 16 around it, falling back to bilinear where one of the 16 is nodata. A point is inside the image
// when -0.5 <= x <= width - 0.5 and likewise y (the image's pixels' area): the outer half pixel repeats the
// edge pixel. Nodata: where the point is outside the image, the height unknown (off the DEM, the geoid grid),
// the model far outside its validity box (normalized |lon| or |lat| above 3: a cubic folded back, not a
// view), or a sample it needs is the image's nodata (GDAL_NODATA, or NaN). A valid result equal to the
// output's nodata value is moved one step off it (integer samples), as GDAL's warper does.
// Work: tiles of 256 x 256 output pixels on `threads` workers; a tile's ground points are exact on a lattice
// every 16 pixels (PROJ) and bilinear between (the map projection is smooth: below 1e-6 m over 16 pixels),
// its heights exact at every pixel, its projections too with a DEM; at a flat height the projection is
// exact at the lattice's nodes and bilinear between them in each lattice cell where that is within 0.001 px
// of the exact value at the cell's centre (every cell, on the crops tried), exact elsewhere. A tile reads
// only the image window its pixels see, so memory is bounded by the tile, not the scene. Hidden ground
// (hide_occluded): each tile's heights are taken again over a window stretched towards the sensor by the
// DEM's relief along the tile's line of sight (at most 512 pixels), and every pixel's ray is followed over it.
#pragma once
#include <cmath>
#include <string>

#include "tpkit/ortho/ortho_geotiff.hpp"
#include "tpkit/ortho/ortho_grid.hpp"
#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

class ReferenceDem;

enum class Resampling { bilinear, bicubic };
// "bilinear" | "bicubic"; UsageError otherwise.
Resampling parse_resampling(const std::string&);

// The heights: a DEM when `dem` is set, else `height` everywhere.
struct OrthoSurface {
  const ReferenceDem* dem = nullptr;
  double height = 0;  // metres above the ellipsoid
  // The surface's highest height over the grid, for hidden ground (OrthoOptions::hide_occluded): set it once
  // for the images of a run (highest_height); NaN: orthorectify finds it for each image.
  double top = NAN;
};

// The surface's highest height over `grid`: the DEM sampled every 4 grid pixels or more (at most about a
// million samples; a peak missed only shortens the search for occluders by its excess); NaN without any
// height; `height` without a DEM.
double highest_height(const OrthoSurface& surface, const OrthoGrid& grid, const GridCrs& crs);

struct OrthoOptions {
  Resampling resampling = Resampling::bilinear;
  int threads = 1;
  // With a DEM: ground the view cannot see (occlusion.hpp: behind a building, a tree, a ridge) written as
  // nodata, not as the surface that hides it; `hidden_tolerance` metres: how far the surface must rise above
  // the line of sight to hide a point (the DEM's own noise and interpolation at roof edges stay below it)
  // and the DEM's walls (slopes above `wall_slope_deg`): a vertical face at a DEM's posting is a ramp a pixel or
  // two wide whose ground points land on the wall in the image, a strip of wall on the roof's edge on the
  // side of the sensor, different for every view (90: none)
  bool hide_occluded = false;
  double hidden_tolerance = 0.5;
  double wall_slope_deg = 60;
  // output nodata: the image's own nodata when it has one, else 0 for integer samples, NaN for floats
  std::string description;  // the GeoTIFF's ImageDescription
};

struct OrthoStats {
  long pixels = 0;     // of the grid
  long valid = 0;      // written from the image
  long no_height = 0;  // nodata because the surface had no height there
  long hidden = 0;     // nodata because the view cannot see the ground there (OrthoOptions::hide_occluded)
  int bands = 0;
  std::string type;    // the sample type written
  double nodata = 0;
};

// Orthorectifies `image` (every band, its sample type kept) through `model` onto `grid` and writes `out`
// (ortho_geotiff.hpp; atomic). InputError for an unreadable image or sample type not written.
OrthoStats orthorectify(const std::string& image, const RpcModel& model, const OrthoGrid& grid, const GridCrs& crs,
                        const OrthoSurface& surface, const OrthoOptions& options, const std::string& out);

}  // namespace tpkit
