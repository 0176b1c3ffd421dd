// A run's outputs commit together: a device that fails when written (/dev/full) leaves none of the files
// and no folder the run made (issue 50, item 6).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

TEST(AtomicOutput, AFailingDeviceLeavesNoFile) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const fs::path dir = fs::temp_directory_path() / ("tpkit-atomic-output-test-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  begin_outputs();
  create_output_dir((dir / "made/sub").string());
  write_file_atomic((dir / "a.txt").string(), "a\n");
  write_file_atomic((dir / "made/sub/b.txt").string(), "b\n");
  {
    AtomicOutput device("/dev/full");
    device.stream() << "text\n";
    device.commit();  // held until the run commits
  }
  try {
    commit_outputs();
    FAIL() << "the write to /dev/full must fail";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/full: write error"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(dir)) << "a.txt, made/ or a temporary file was left";
  fs::remove_all(dir);
}

TEST(AtomicOutput, FilesAndDeviceCommitTogether) {
  const fs::path dir = fs::temp_directory_path() / ("tpkit-atomic-output-test-ok-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  begin_outputs();
  write_file_atomic((dir / "a.txt").string(), "a\n");
  write_file_atomic("/dev/null", "text\n");
  EXPECT_FALSE(fs::exists(dir / "a.txt"));  // not before the commit
  commit_outputs();
  EXPECT_TRUE(fs::exists(dir / "a.txt"));
  fs::remove_all(dir);
}
