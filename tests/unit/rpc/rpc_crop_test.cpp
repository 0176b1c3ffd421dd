// tp-rpc crop's library (rpc_crop.hpp) on the real Pléiades crop img_01: the window's pixels are the
// image's, the shifted model maps every ground point to the same pixel less the window's corner, and
// windows outside the image or float samples are refused.
#include "tpkit/rpc/rpc_crop.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_io.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {
const std::string kImage = std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille/img_01.tif";
std::string scratch(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("tpkit-rpc-crop-test-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return (d / name).string();
}
}  // namespace

TEST(RpcCrop, PixelsAndModelOfTheWindow) {
  const RpcModel m = *read_rpc_tiff(kImage);
  const std::string out = scratch("crop.tif");
  crop_image_with_rpc(kImage, 0, m, 100, 200, 300, 250, out);
  const ImageInfo info = image_info(out);
  EXPECT_EQ(info.width, 300);
  EXPECT_EQ(info.height, 250);
  EXPECT_EQ(info.format, "uint16");
  EXPECT_EQ(read_band(out).data, read_region(kImage, 0, 100, 200, 300, 250).data);
  const RpcModel c = *read_rpc_tiff(out);
  for (double h : {50.0, 200.0, 350.0})
    for (double f : {-0.8, 0.0, 0.7}) {
      const double lon = m.lon_off + f * m.lon_scale, lat = m.lat_off - f * m.lat_scale;
      const Eigen::Vector2d d = c.project(lon, lat, h) - (m.project(lon, lat, h) - Eigen::Vector2d(100, 200));
      EXPECT_LT(d.norm(), 1e-9) << "h " << h << " f " << f;
    }
}

TEST(RpcCrop, WindowsOutsideTheImageAndFloatSamplesAreRefused) {
  const RpcModel m = *read_rpc_tiff(kImage);
  EXPECT_THROW(crop_image_with_rpc(kImage, 0, m, 900, 0, 200, 10, scratch("a.tif")), InputError);
  EXPECT_THROW(crop_image_with_rpc(kImage, 0, m, -1, 0, 10, 10, scratch("b.tif")), InputError);
  EXPECT_THROW(crop_image_with_rpc(kImage, 0, m, 0, 0, 0, 10, scratch("c.tif")), InputError);
  EXPECT_THROW(crop_image_with_rpc(kImage, 1, m, 0, 0, 10, 10, scratch("d.tif")), InputError);
  GeoGrid g;
  g.width = g.height = 4;
  g.data.assign(16, 1.5f);
  const std::string dem = scratch("dem.tif");
  write_geotiff_grid(dem, g);
  EXPECT_THROW(crop_image_with_rpc(dem, 0, m, 0, 0, 2, 2, scratch("e.tif")), InputError);
  EXPECT_FALSE(fs::exists(scratch("a.tif")));
}
