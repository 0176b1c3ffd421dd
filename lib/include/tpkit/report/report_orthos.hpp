// The orthoimages of a block in place on the tp-report page: orthos of "before" and of "after" the
// adjustment (tp-ortho's GeoTIFFs, or any GeoTIFFs of one grid), shown as
//   - thumbnails, one per ortho, with its share of valid pixels;
//   - a flicker between the dates, before and after side by side: an inline SVG whose frames (one per
//     image, an embedded JPEG and its name) are shown in turn by a CSS animation, no script; once over
//     the whole grid, once over its centre at full resolution, where a shift of a pixel shows;
//   - a checkerboard of two dates (the first two images by name), squares taken in turn from each;
//   - the images' footprints on one lon/lat frame: from the RPC model of the image the ortho was made of
//     (an image of the run's files whose stem is the ortho's name, localized along its border at the
//     model's HEIGHT_OFF), else the outline of the ortho's valid pixels.
// An ortho's name is its file name less ".ortho.tif" (tp-ortho's <image stem>.ortho.tif), else less its
// extension; before and after are paired by name. All orthos of a set lie on one grid (same CRS, size and
// geotransform), so that the frames overlay pixel for pixel; one that does not is refused.
// Pixels: a frame pixel (u, v) is the mean of the valid grid pixels it covers (f x f, f the reduction);
// grey levels stretched per image from its 2nd to 98th percentile over every band (band 1 alone for an
// image of fewer than 3 bands, bands 1 to 3 as red, green, blue otherwise); nodata (the GDAL_NODATA tag:
// a pixel whose bands all hold it; NaN) is drawn light grey.
#pragma once
#include <string>
#include <vector>

namespace tpkit {

struct OrthoOptions {
  int thumb_px = 200;       // thumbnails, longer side
  int frame_px = 560;       // flicker over the whole grid and checkerboard, longer side
  int zoom_px = 280;        // flicker of the grid's centre at full resolution, side
  double frame_s = 0.7;     // seconds each flicker frame is shown
  int checker_cells = 8;    // squares along the longer side of the checkerboard
  int jpeg_quality = 88;
  // Images of the run (the paths in its files' headers): where a footprint's RPC model is looked for.
  std::vector<std::string> images;
};

// The orthos an option names: each argument a GeoTIFF file, or a folder whose *.ortho.tif files are taken
// (not recursive, sorted by name). InputError naming `option` and the argument for one that does not exist or
// a folder without any.
std::vector<std::string> ortho_inputs(const std::vector<std::string>& args, const std::string& option);

// The section (HTML, images inline). InputError naming the file for one that is not a georeferenced GeoTIFF,
// not on the grid of its set's first ortho, or whose name comes twice in a set.
std::string orthos_html(const std::vector<std::string>& before, const std::vector<std::string>& after, const OrthoOptions& options);

}  // namespace tpkit
