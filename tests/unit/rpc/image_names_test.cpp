// How a reference names one of the given images (image_index): the one rule of tracks and GCP files' image
// lines, --rpc IMAGE=FILE and --fixed (issue 50, item 15).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "tpkit/core/error.hpp"
#include "tpkit/rpc/rpc_io.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {
// a scratch folder with d/a.tif, d/b.tif, e/a.tif and a link l.tif -> d/b.tif; the test runs in it
struct Scratch {
  fs::path dir, before;
  Scratch() {
    before = fs::current_path();
    dir = fs::temp_directory_path() / ("tpkit-image-names-test-" + std::to_string(::getpid()));
    fs::create_directories(dir / "d");
    fs::create_directories(dir / "e");
    for (const char* f : {"d/a.tif", "d/b.tif", "e/a.tif"}) std::ofstream(dir / f) << "x";
    fs::create_symlink("d/b.tif", dir / "l.tif");
    fs::current_path(dir);
  }
  ~Scratch() {
    fs::current_path(before);
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};
}  // namespace

TEST(ImageNames, TheSameFileUnderAnyName) {
  Scratch s;
  const std::vector<std::string> images = {"d/a.tif", "d/b.tif"};
  EXPECT_EQ(image_index("d/b.tif", images), 1);
  EXPECT_EQ(image_index("./d/b.tif", images), 1);
  EXPECT_EQ(image_index((s.dir / "d/b.tif").string(), images), 1);
  EXPECT_EQ(image_index("d/../d/a.tif", images), 0);
  EXPECT_EQ(image_index("l.tif", images), 1);  // a link to it
  EXPECT_EQ(image_index("b.tif", images, "d/t.tracks"), 1);  // relative to the file that names it
  EXPECT_EQ(image_index("elsewhere/b.tif", images), 1);      // else the one image of that name
  EXPECT_EQ(image_index("c.tif", images), -1);
  EXPECT_EQ(image_index("x/a.tif", {"d/a.tif", "e/a.tif"}), -2);  // two images of that name
}

TEST(ImageNames, RpcOverridesAreKeyedByTheImageAsGiven) {
  Scratch s;
  const std::vector<std::string> images = {"d/a.tif", "d/b.tif"};
  const auto o = resolve_rpc_overrides(parse_rpc_overrides({"./d/b.tif=b_rpc.txt", "d/a.tif=a_rpc.txt"}), images);
  EXPECT_EQ(o, (std::map<std::string, std::string>{{"d/a.tif", "a_rpc.txt"}, {"d/b.tif", "b_rpc.txt"}}));
  // two names of one image, and a name of none, are refused
  EXPECT_THROW(resolve_rpc_overrides(parse_rpc_overrides({"./d/b.tif=x", "l.tif=y"}), images), UsageError);
  try {
    resolve_rpc_overrides(parse_rpc_overrides({"d/c.tif=x"}), images);
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_STREQ(e.what(), "--rpc d/c.tif=x: d/c.tif is not one of the images");
  }
}
