// Tests of input_file.hpp beyond the tool cases: TextInput gives back exactly the bytes of its input,
// across its read-ahead blocks and from a pipe read once; a device fails at its first line; an image
// path must be a regular file; a std::filesystem error in the project's words.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <system_error>
#include <thread>

#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/text_table.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {
fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("tpkit-input-file-test-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

// A tracks file of `n` records, larger than TextInput's read-ahead block of 64 KiB for n >= 2000.
std::string tracks_text(int n) {
  std::string s = "# tpkit tracks 1\n# columns: track x1 y1 x2 y2\n";
  for (int k = 0; k < n; ++k)
    s += std::to_string(k) + " " + std::to_string(k * 0.25) + " 17.5 " + std::to_string(k + 3) + " 1234.0625\n";
  return s;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(TextInput, GivesBackTheFirstLineThenTheRestAcrossBlocks) {
  const std::string text = tracks_text(20000);  // about 600 KB: ten blocks
  ASSERT_GT(text.size(), size_t(10) << 16);
  const fs::path p = scratch("big.tracks");
  std::ofstream(p, std::ios::binary) << text;
  TextInput in(p.string());
  EXPECT_EQ(in.first_line(), "# tpkit tracks 1");
  EXPECT_EQ(in.header_kind(), "tracks");
  const std::string back((std::istreambuf_iterator<char>(in.stream())), std::istreambuf_iterator<char>());
  EXPECT_EQ(back, text);
}

TEST(TextInput, ReadsAPipeOnce) {
  // a FIFO opened once: the table parsed from the stream holds every record, the first line included
  const fs::path p = scratch("tracks.fifo");
  fs::remove(p);
  ASSERT_EQ(::mkfifo(p.c_str(), 0600), 0);
  const std::string text = tracks_text(5000);
  std::thread writer([&] { std::ofstream(p, std::ios::binary) << text; });
  TextInput in(p.string());
  const TextTable t = read_table(in.stream(), p.string(), tracks_read_options());
  writer.join();
  EXPECT_EQ(t.kind, "tracks");
  EXPECT_EQ(t.rows.size(), 5000u);
  EXPECT_EQ(t.row_line.back(), 5002);
}

TEST(TextInput, HeaderKindOfOtherFirstLines) {
  EXPECT_EQ(tpkit_header_kind("# tpkit matches 1"), "matches");
  EXPECT_EQ(tpkit_header_kind("#  tpkit  rpc-residuals  1 "), "rpc-residuals");
  EXPECT_EQ(tpkit_header_kind("# tpkit plan (tp-plan): make -C WORK"), "");  // a makefile's comment
  EXPECT_EQ(tpkit_header_kind("# tpkit matches"), "");
  EXPECT_EQ(tpkit_header_kind("1 2 3 4 5 6"), "");
  const fs::path p = scratch("bom.matches");
  std::ofstream(p, std::ios::binary) << "\xEF\xBB\xBF# tpkit matches 1\n";
  EXPECT_EQ(TextInput(p.string()).header_kind(), "matches");
}

TEST(TextInput, DeviceFailsAtItsFirstLine) {
  EXPECT_EQ(error_of([] { TextInput in("/dev/zero"); }), "/dev/zero:1: binary data (NUL byte) in a text file");
}

TEST(InputFile, AnImageMustBeARegularFile) {
  EXPECT_EQ(error_of([] { check_input_file("/dev/zero", InputKind::image); }),
            "/dev/zero: not a regular file: an image must be a file");
  EXPECT_EQ(error_of([] { check_input_file(scratch("none.tif").string(), InputKind::image); }),
            scratch("none.tif").string() + ": no such file");
}

TEST(InputFile, FilesystemErrorInTheProjectsWords) {
  const fs::filesystem_error e("status", fs::path("run/loop"), std::make_error_code(std::errc::too_many_symbolic_link_levels));
  EXPECT_EQ(filesystem_error_message(e), "run/loop: status: Too many levels of symbolic links");
  const fs::filesystem_error two("cannot copy", fs::path("a"), fs::path("b"), std::make_error_code(std::errc::file_exists));
  EXPECT_EQ(filesystem_error_message(two), "a, b: cannot copy: File exists");
}
