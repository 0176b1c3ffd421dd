// A window of an image together with its RPC model (rpcm's crop): the pixels of [x0, x0 + w) x
// [y0, y0 + h) of one band as a 16-bit GeoTIFF, its model shifted so that it maps the ground to the
// crop's pixels (SAMP_OFF - x0, LINE_OFF - y0: RPC00B and tpkit share the pixel convention, (0, 0) the
// centre of the top-left pixel) in tag 50844. Samples must be integers of at most 16 bits (uint8 and
// uint16 images; they are written as uint16, values unchanged). Read and written row strip by row strip:
// memory bounded by a strip, whatever the window.
// An output named *.ntf / *.nitf is a NITF 2.1 image instead (nitf_image.hpp: uncompressed or lossless
// JPEG 2000, its ABPP the source's bits) with the model in an RPC00B TRE (rpc_nitf.hpp), which holds
// offsets, scales and coefficients at a fixed precision: the model is renormalized to it, and refused
// when that moves a projection by more than kMaxNitfRpcChangePx anywhere in its validity volume.
#pragma once
#include <string>

#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

// The model of a window whose top-left pixel is (x0, y0) of the image.
RpcModel shift_rpc_model(const RpcModel& m, double x0, double y0);

constexpr double kMaxNitfRpcChangePx = 0.01;
struct CropFormat {
  bool jpeg2000 = false;  // NITF output: IC = C8 (lossless) instead of NC
  long block = 1024;      // NITF output: block / tile size, pixels
};
// True for a NITF output name (.ntf, .nitf, any case).
bool is_nitf_name(const std::string& path);
// Returns how much the written model's projections differ from the shifted model's (0 for a GeoTIFF;
// for NITF, the RPC00B precision), pixels. Throws InputError (the image) for a window outside it or
// samples that are not integers of <= 16 bits.
double crop_image_with_rpc(const std::string& image, int band, const RpcModel& model, long x0, long y0, long w, long h,
                           const std::string& out, const CropFormat& format = {});

}  // namespace tpkit
