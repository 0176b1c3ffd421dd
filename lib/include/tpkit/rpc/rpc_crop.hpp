// A window of an image together with its RPC model (rpcm's crop): the pixels of [x0, x0 + w) x
// [y0, y0 + h) of one band as a 16-bit GeoTIFF, its model shifted so that it maps the ground to the
// crop's pixels (SAMP_OFF - x0, LINE_OFF - y0: RPC00B and tpkit share the pixel convention, (0, 0) the
// centre of the top-left pixel) in tag 50844. Samples must be integers of at most 16 bits (uint8 and
// uint16 images; they are written as uint16, values unchanged). Read and written row strip by row strip:
// memory bounded by a strip, whatever the window.
#pragma once
#include <string>

#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

// The model of a window whose top-left pixel is (x0, y0) of the image.
RpcModel shift_rpc_model(const RpcModel& m, double x0, double y0);

// Throws InputError (the image) for a window outside it or samples that are not integers of <= 16 bits.
void crop_image_with_rpc(const std::string& image, int band, const RpcModel& model, long x0, long y0, long w, long h,
                         const std::string& out);

}  // namespace tpkit
