// Private to the ground component: what the GeoTIFF tags of an open file say, shared by the reference DEM
// reader (reference_dem.cpp) and the grid of any GeoTIFF (geotiff_georef.cpp).
#pragma once
#include <array>
#include <string>

typedef struct tiff TIFF;
typedef struct gtiff GTIF;

namespace tpkit {

// The affine map of pixel centres (tpkit pixels: (0, 0) the centre of the top-left pixel) to model
// coordinates, x = a0 + a1 c + a2 r, y = a3 + a4 c + a5 r, from ModelTransformation, else one tie point and
// the pixel scale (rows run towards -y), the raster type's half pixel applied. InputError naming `path`
// when the tags give no regular grid or a degenerate one.
std::array<double, 6> geotiff_pixel_to_model(TIFF* tif, GTIF* gtif, const std::string& path);

}  // namespace tpkit
