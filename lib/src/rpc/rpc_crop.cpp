// See rpc_crop.hpp.
#include "tpkit/rpc/rpc_crop.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_io.hpp"

namespace tpkit {

RpcModel shift_rpc_model(const RpcModel& m, double x0, double y0) {
  RpcModel s = m;
  s.samp_off -= x0;
  s.line_off -= y0;
  s.has_direct = false;  // the direct model's inputs were the old pixels; refitted by writers that need one
  return s;
}

void crop_image_with_rpc(const std::string& image, int band, const RpcModel& model, long x0, long y0, long w, long h,
                         const std::string& out) {
  const ImageInfo info = image_info(image);
  if (band < 0 || band >= info.bands)
    throw InputError(image, 0, "band " + std::to_string(band + 1) + " does not exist (" + std::to_string(info.bands) + " bands)");
  if (info.format != "uint8" && info.format != "uint16")
    throw InputError(image, 0, "samples of type " + info.format + ": the crop writes integers of at most 16 bits");
  if (w <= 0 || h <= 0 || x0 < 0 || y0 < 0 || x0 + w > info.width || y0 + h > info.height)
    throw InputError(image, 0, "the window " + std::to_string(x0) + " " + std::to_string(y0) + " " + std::to_string(w) + " " +
                                   std::to_string(h) + " is not inside the image (" + std::to_string(info.width) + " x " +
                                   std::to_string(info.height) + ")");
  TiffWriterU16 writer(out, w, h);
  writer.set_rpc_tag(rpc_tag_values(shift_rpc_model(model, static_cast<double>(x0), static_cast<double>(y0))));
  const long strip = std::max(1L, std::min(h, (long(1) << 22) / std::max(1L, w)));  // about 4 M samples per strip
  std::vector<uint16_t> rows;
  for (long y = 0; y < h; y += strip) {
    const long n = std::min(strip, h - y);
    const Raster r = read_region(image, band, x0, y0 + y, w, n);
    rows.resize(r.data.size());
    std::transform(r.data.begin(), r.data.end(), rows.begin(), [](float v) { return static_cast<uint16_t>(v); });
    writer.write_rows(y, n, rows.data());
  }
  writer.close();
}

}  // namespace tpkit
