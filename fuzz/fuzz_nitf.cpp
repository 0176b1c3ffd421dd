// libFuzzer target for the NITF reader (nitf_image.hpp) and its RPC00B TRE (rpc_nitf.hpp): the bytes
// are written to a file (the reader reads files, by offset), then the headers, the image information,
// a few regions of every band and the model are read. Any input must either be read or raise
// tpkit::InputError; a crash, a sanitizer report, another exception or a read past the file is a bug.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/nitf_image.hpp"
#include "tpkit/rpc/rpc_nitf.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = "/tmp/fuzz_nitf." + std::to_string(::getpid()) + ".ntf";
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  try {
    const tpkit::NitfImage im = tpkit::read_nitf_image(path);
    try {
      (void)tpkit::read_rpc_nitf(im);
    } catch (const tpkit::InputError&) {
    }
    const tpkit::ImageInfo info = tpkit::nitf_image_info(im);
    for (int b = 0; b < std::min(info.bands, 4); ++b) {
      (void)tpkit::read_nitf_region(im, b, 0, 0, 16, 16);
      (void)tpkit::read_nitf_region(im, b, info.width - 5, info.height - 7, 16, 16);
      (void)tpkit::read_nitf_region(im, b, info.width / 2, info.height / 2, 9, 3);
    }
  } catch (const tpkit::InputError&) {
  }
  return 0;
}
