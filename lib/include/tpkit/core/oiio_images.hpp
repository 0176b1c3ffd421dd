// Images in the formats OpenImageIO reads and writes other than TIFF and NITF (PNG, JPEG, OpenEXR, ...,
// and TIFF layouts tiff_image.hpp leaves to it), through tpkit's OpenImageIO module (tpkit_oiio.so)
// loaded on the first call: Debian's OpenImageIO brings some 250 libraries whose loading costs about
// 0.37 s, which no tool should pay for files it does not read.
//
// The module is looked for, in order, at $TPKIT_OIIO_MODULE, at <the executable's folder>/../lib/tpkit
// (the installed layout, and the build tree's: bin/ beside lib/tpkit/), and at the installed path. A
// missing module is an InputError naming the image and the places looked at.
#pragma once
#include <string>
#include <vector>

#include "tpkit/core/image_io.hpp"

namespace tpkit {

ImageInfo oiio_image_info(const std::string& path);
// Band `band` of the region, clipped to the image (as read_region).
Raster oiio_read_region(const std::string& path, int band, long x0, long y0, long w, long h);
// Writes a single-band 8- or 16-bit image to `file` (its format from the extension) as given: atomicity
// is the caller's; errors name `path`.
void oiio_write_image(const std::string& file, const std::string& path, long width, long height, int bits, const void* data);

// The module's candidate paths, in the order tried.
std::vector<std::string> oiio_module_candidates();

}  // namespace tpkit
