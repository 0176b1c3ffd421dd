// See rpc_crop.hpp.
#include "tpkit/rpc/rpc_crop.hpp"

#include <algorithm>
#include <cctype>
#include <memory>
#include <cmath>
#include <filesystem>
#include <vector>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/nitf_image.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/rpc/rpc_nitf.hpp"

namespace tpkit {

RpcModel shift_rpc_model(const RpcModel& m, double x0, double y0) {
  RpcModel s = m;
  s.samp_off -= x0;
  s.line_off -= y0;
  s.has_direct = false;  // the direct model's inputs were the old pixels; refitted by writers that need one
  return s;
}

bool is_nitf_name(const std::string& path) {
  std::string ext = path.substr(path.find_last_of('.') == std::string::npos ? path.size() : path.find_last_of('.'));
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".ntf" || ext == ".nitf";
}

double crop_image_with_rpc(const std::string& image, int band, const RpcModel& model, long x0, long y0, long w, long h,
                           const std::string& out, const CropFormat& format) {
  const ImageInfo info = image_info(image);
  if (band < 0 || band >= info.bands)
    throw InputError(image, 0, "band " + std::to_string(band + 1) + " does not exist (" + std::to_string(info.bands) + " bands)");
  if (info.format != "uint8" && info.format != "uint16")
    throw InputError(image, 0, "samples of type " + info.format + ": the crop writes integers of at most 16 bits");
  if (w <= 0 || h <= 0 || x0 < 0 || y0 < 0 || x0 + w > info.width || y0 + h > info.height)
    throw InputError(image, 0, "the window " + std::to_string(x0) + " " + std::to_string(y0) + " " + std::to_string(w) + " " +
                                   std::to_string(h) + " is not inside the image (" + std::to_string(info.width) + " x " +
                                   std::to_string(info.height) + ")");
  // A header's sizes are no measure of the pixels a file holds: a NITF may declare 99999999 x 99999999
  // pixels in blocks its mask leaves out (pad), in a few kilobytes, and a crop takes time and output in
  // proportion to its window. No codec stores real pixels at a million per byte (deflate's limit is about
  // a thousand): a window beyond that is padding, refused before any work.
  constexpr double kMaxPixelsPerByte = 1 << 20;
  std::error_code ec;
  const double file_bytes = static_cast<double>(std::filesystem::file_size(image, ec));
  if (!ec && static_cast<double>(w) * static_cast<double>(h) > kMaxPixelsPerByte * std::max(1.0, file_bytes))
    throw InputError(image, 0, "the window of " + std::to_string(w) + " x " + std::to_string(h) + " pixels is more than " +
                                   std::to_string(static_cast<long>(kMaxPixelsPerByte)) + " pixels per byte of the file (" +
                                   std::to_string(static_cast<long>(file_bytes)) + " bytes): padding or blocks the file leaves out, " +
                                   "not pixels it holds");
  const RpcModel shifted = shift_rpc_model(model, static_cast<double>(x0), static_cast<double>(y0));
  double change = 0;
  std::unique_ptr<TiffWriterU16> tiff;
  std::unique_ptr<NitfWriterU16> nitf;
  if (is_nitf_name(out)) {
    const RpcTre tre = format_rpc00b_tre(shifted);
    change = tre.max_change_px;
    if (change > kMaxNitfRpcChangePx)
      throw InputError(out, 0, "the RPC00B TRE's fixed precision would move the model's projections by up to " +
                                   std::to_string(change) + " px in its validity volume (more than " +
                                   std::to_string(kMaxNitfRpcChangePx) + "): write a GeoTIFF instead");
    NitfWriteOptions o;
    o.compression = format.jpeg2000 ? NitfWriteOptions::Compression::j2k : NitfWriteOptions::Compression::none;
    o.block = format.block;
    o.abpp = info.bits >= 1 && info.bits <= (info.format == "uint8" ? 8 : 16) ? info.bits : (info.format == "uint8" ? 8 : 16);
    o.tres.push_back(tre.tre);
    nitf = std::make_unique<NitfWriterU16>(out, w, h, o);
  } else {
    tiff = std::make_unique<TiffWriterU16>(out, w, h);
    tiff->set_rpc_tag(rpc_tag_values(shifted));
  }
  const long strip = std::max(1L, std::min(h, (long(1) << 22) / std::max(1L, w)));  // about 4 M samples per strip
  std::vector<uint16_t> rows;
  for (long y = 0; y < h; y += strip) {
    const long n = std::min(strip, h - y);
    const Raster r = read_region(image, band, x0, y0 + y, w, n);
    rows.resize(r.data.size());
    std::transform(r.data.begin(), r.data.end(), rows.begin(), [](float v) { return static_cast<uint16_t>(v); });
    if (nitf)
      nitf->write_rows(y, n, rows.data());
    else
      tiff->write_rows(y, n, rows.data());
  }
  if (nitf)
    nitf->close();
  else
    tiff->close();
  return change;
}

}  // namespace tpkit
