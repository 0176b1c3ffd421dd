// ASP / VisionWorkbench match files: the binary layout pinned byte by byte, round trips, bad input.
#include "tpkit/interop/asp_match.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "sample_matches.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/interop/peer_keypoints.hpp"

using namespace tpkit;
using tpkit_test::f32;

namespace {

std::string write_file(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

Matches one_match() {
  Matches m;
  m.image1 = {"a/left.tif", 10, 10};
  m.image2 = {"right.tif", 10, 10};
  m.id1 = {4};
  m.id2 = {9};
  m.xy.resize(1, 4);
  m.xy << 10.25, -3.5, 1000.125, 20.75;
  m.extra.names = {"sigma"};
  m.extra.values.resize(1, 1);
  m.extra.values << 0.05;  // floored to 0.1
  return m;
}

}  // namespace

TEST(AspMatch, BinaryLayoutByteByByte) {
  std::ostringstream os;
  write_asp_match(os, one_match(), 0.1);
  // Hand-computed: uint64 1, uint64 1, then per image: float32 x, y; int32 ix, iy; float32 orientation,
  // scale, interest; uint8 polarity; uint32 octave, scale_lvl; uint64 ndesc = 0. Little-endian.
  //   10.25f = 0x41240000, -3.5f = 0xc0600000, round -> 10, -4 (0xfffffffc), 0.1f = 0x3dcccccd
  //   1000.125f = 0x447a0800, 20.75f = 0x41a60000, round -> 1000 (0x3e8), 21 (0x15)
  const std::string header = "0100000000000000" "0100000000000000";
  const std::string rec1 = "00002441" "000060c0" "0a000000" "fcffffff" "00000000" "cdcccc3d" "00000000" "00" "00000000"
                           "00000000" "0000000000000000";
  const std::string rec2 = "00087a44" "0000a641" "e8030000" "15000000" "00000000" "cdcccc3d" "00000000" "00" "00000000"
                           "00000000" "0000000000000000";
  EXPECT_EQ(tpkit_test::hex(os.str()), header + rec1 + rec2);
  EXPECT_EQ(os.str().size(), 16 + 2 * kAspRecordBytes);
}

TEST(AspMatch, FileNameFromStems) {
  EXPECT_EQ(asp_match_file_name("run/run", "/d/img_01.tif", "img_02.tif", false), "run/run-img_01__img_02.match");
  EXPECT_EQ(asp_match_file_name("out", "x/a.b.tif", "c", true), "out-a.b__c.txt");
}

TEST(AspMatch, BinaryRoundTripToFloat32) {
  const std::string dir = tpkit_test::scratch_dir("asp");
  const Matches m = tpkit_test::sample_matches("/data/img_01.tif", "img_02.tif", 50, 3);
  std::ostringstream os;
  write_asp_match(os, m, 0.1);
  const std::string path = write_file(dir + "/run-img_01__img_02.match", os.str());
  std::vector<Matches> back = {read_asp_match(path)};
  assign_position_ids(back);
  const Matches& b = back[0];
  EXPECT_EQ(b.image1.path, "img_01");
  EXPECT_EQ(b.image2.path, "img_02");
  EXPECT_EQ(meta_get(b.meta, "source-format"), "asp");
  ASSERT_EQ(b.size(), m.size());
  for (size_t r = 0; r < m.size(); ++r) {
    for (int c = 0; c < 4; ++c) EXPECT_EQ(b.xy(r, c), f32(m.xy(r, c))) << r << " " << c;
    EXPECT_EQ(b.extra.values(r, b.extra.find("sigma")), f32(std::max(0.1, m.extra.values(r, 0))));
    EXPECT_EQ(b.id1[r], static_cast<long long>(r));  // distinct positions: ids by first appearance
  }
  // --images stems that hold '-' and a prefix with '-'
  const std::string odd = write_file(dir + "/my-run-img-a__img-b.match", os.str());
  EXPECT_EQ(read_asp_match(odd, {"/x/img-a.tif"}).image1.path, "img-a");
  EXPECT_EQ(read_asp_match(odd).image1.path, "a");
}

TEST(AspMatch, TextRoundTripExact) {
  const std::string dir = tpkit_test::scratch_dir("asp-txt");
  const Matches m = tpkit_test::sample_matches("img_01.tif", "img_02.tif", 20, 4);
  std::ostringstream os;
  write_asp_match_text(os, m, 0.1);
  const Matches b = read_asp_match(write_file(dir + "/p-img_01__img_02.txt", os.str()));
  EXPECT_EQ(meta_get(b.meta, "source-format"), "asp-txt");
  ASSERT_EQ(b.size(), m.size());
  // ASP's own reader parses floats; ours keeps the doubles written
  for (size_t r = 0; r < m.size(); ++r)
    for (int c = 0; c < 4; ++c) EXPECT_EQ(b.xy(r, c), m.xy(r, c));
}

TEST(AspMatch, BadInput) {
  const std::string dir = tpkit_test::scratch_dir("asp-bad");
  std::ostringstream os;
  write_asp_match(os, one_match(), 0.1);
  const std::string good = os.str();
  auto fails_with = [&](const std::string& name, const std::string& bytes, const std::string& what) {
    const std::string path = write_file(dir + "/" + name, bytes);
    tpkit_test::expect_input_error([&] { read_asp_match(path); }, path, what);
  };
  fails_with("p-a__b.match", good.substr(0, good.size() - 1), "truncated");
  fails_with("q-a__b.match", good.substr(0, 12), "truncated");
  std::string counts = good;
  counts[8] = 2;  // n2 = 2
  fails_with("r-a__b.match", counts, "counts disagree");
  fails_with("s-a__b.match", good + "x", "after the last record");
  fails_with("nounderscores.match", good, "no '__'");
  fails_with("t-a__b.txt", "1 2 0.5 3 4\n", "six numbers");
  fails_with("u-a__b.txt", "1 2 0 3 4 1\n", "must be finite and > 0");
  // non-finite values (issue 23: a NaN scale went into the sigma column): the first record's scale at byte 36
  std::string nan_scale = good;
  nan_scale.replace(36, 4, std::string("\0\0\xc0\x7f", 4));
  fails_with("v-a__b.match", nan_scale, "holds a non-finite scale");
}
