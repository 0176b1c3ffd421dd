// MicMac Homol files: the .dat layout (8-byte header, 44-byte records, from MicMac's own
// cPackNupletsHom::read) pinned byte by byte, both directions, round trips, bad input.
#include "tpkit/interop/micmac_homol.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "sample_matches.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/interop/peer_keypoints.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {

Matches one_pair() {
  Matches m;
  m.image1 = {"d/A.tif", 10, 10};
  m.image2 = {"B.tif", 10, 10};
  m.id1 = {0};
  m.id2 = {0};
  m.xy.resize(1, 4);
  m.xy << 1.5, 2, -0.25, 1024;
  return m;
}

std::string written(const Matches& m, bool binary, bool reversed) {
  std::ostringstream os;
  write_micmac_homol(os, m, binary, reversed);
  return os.str();
}

void put(const std::string& path, const std::string& bytes) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << bytes;
}

}  // namespace

TEST(MicmacHomol, DatLayoutByteByByte) {
  // int32 dim 2, int32 N 1 | int32 2, float64 weight 1 (0x3ff0000000000000), float64 x1 1.5
  // (0x3ff8...), y1 2 (0x4000...), x2 -0.25 (0xbfd0...), y2 1024 (0x4090...); little-endian
  const std::string expect = "02000000" "01000000" "02000000" "000000000000f03f" "000000000000f83f" "0000000000000040"
                             "000000000000d0bf" "0000000000009040";
  const std::string bytes = written(one_pair(), true, false);
  EXPECT_EQ(tpkit_test::hex(bytes), expect);
  EXPECT_EQ(bytes.size(), kMicmacHeaderBytes + kMicmacRecordBytes);
  // the other direction: image 2's point first
  EXPECT_EQ(tpkit_test::hex(written(one_pair(), true, true)),
            "02000000" "01000000" "02000000" "000000000000f03f" "000000000000d0bf" "0000000000009040" "000000000000f83f"
            "0000000000000040");
  EXPECT_EQ(written(one_pair(), false, false), "1.5 2 -0.25 1024 1\n");
}

TEST(MicmacHomol, FileNames) {
  EXPECT_EQ(micmac_homol_file_name("Homol", "/d/img_01.tif", "img_02.tif", true), "Homol/Pastisimg_01.tif/img_02.tif.dat");
  EXPECT_EQ(micmac_homol_file_name("H", "a.jpg", "b.jpg", false), "H/Pastisa.jpg/b.jpg.txt");
}

TEST(MicmacHomol, RoundTripBothFormsAndFolder) {
  for (bool binary : {true, false}) {
    const std::string dir = tpkit_test::scratch_dir(binary ? "mm-dat" : "mm-txt");
    Matches m = tpkit_test::sample_matches("/x/img_02.tif", "img_01.tif", 40, 5);
    m.extra.names = {"weight"};  // the weight column travels
    for (bool rev : {false, true})
      put(micmac_homol_file_name(dir + "/Homol", rev ? m.image2.path : m.image1.path, rev ? m.image1.path : m.image2.path, binary),
          written(m, binary, rev));
    // the folder reader takes each pair once, in --images order
    std::vector<Matches> back = read_micmac_homol_folder(dir + "/Homol", {"img_02.tif", "img_01.tif"});
    ASSERT_EQ(back.size(), 1u);
    const Matches& b = back[0];
    EXPECT_EQ(b.image1.path, "img_02.tif");
    EXPECT_EQ(b.image2.path, "img_01.tif");
    EXPECT_EQ(meta_get(b.meta, "source-format"), binary ? "micmac-dat" : "micmac");
    ASSERT_EQ(b.size(), m.size());
    for (size_t r = 0; r < m.size(); ++r) {
      for (int c = 0; c < 4; ++c) EXPECT_EQ(b.xy(r, c), m.xy(r, c));  // float64 and shortest decimals: exact
      EXPECT_EQ(b.extra.values(r, b.extra.find("weight")), m.extra.values(r, 0));
    }
    // name order without --images: img_01 first, read from the reversed file and swapped back
    std::vector<Matches> sorted = read_micmac_homol_folder(dir + "/Homol");
    ASSERT_EQ(sorted.size(), 1u);
    EXPECT_EQ(sorted[0].image1.path, "img_01.tif");
    EXPECT_EQ(sorted[0].xy(3, 0), m.xy(3, 2));
    EXPECT_EQ(sorted[0].xy(3, 3), m.xy(3, 1));
  }
}

TEST(MicmacHomol, PositionIdsJoinPairs) {
  // the same position of image A in two pairs gets one id, so tp-chain joins them
  Matches ab = one_pair(), ac = one_pair();
  ac.image2 = {"C.tif", 10, 10};
  ac.xy(0, 2) = 7;
  std::vector<Matches> v = {ab, ac};
  assign_position_ids(v);
  EXPECT_EQ(v[0].id1[0], v[1].id1[0]);
}

TEST(MicmacHomol, BadInput) {
  const std::string dir = tpkit_test::scratch_dir("mm-bad");
  const std::string good = written(one_pair(), true, false);
  auto fails_with = [&](const std::string& name, const std::string& bytes, const std::string& what) {
    const std::string path = dir + "/Homol/PastisA.tif/" + name;
    put(path, bytes);
    tpkit_test::expect_input_error([&] { read_micmac_homol(path); }, path, what);
  };
  fails_with("B1.tif.dat", good.substr(0, good.size() - 3), "the count says 1 records");
  fails_with("B2.tif.dat", good.substr(0, 6), "truncated");
  std::string n2 = good;
  n2[4] = 2;
  fails_with("B3.tif.dat", n2, "the count says 2 records");
  std::string dim = good;
  dim[0] = 3;
  fails_with("B4.tif.dat", dim, "dim is 3");
  fails_with("B5.tif.txt", "1 2 3\n", "x1 y1 x2 y2");
  fails_with("B6.tif.txt", "1 2 3 4 w\n", "weight is not a number");
  // non-finite values (issue 23: they went into the matches file): the weight at byte 12, x1 at byte 20
  const std::string nan = std::string("\0\0\0\0\0\0\xf8\x7f", 8), inf = std::string("\0\0\0\0\0\0\xf0\x7f", 8);
  fails_with("B7.tif.dat", good.substr(0, 12) + nan + good.substr(20), "record 0 (byte 8) holds a non-finite weight");
  fails_with("B8.tif.dat", good.substr(0, 20) + inf + good.substr(28), "record 0 (byte 8) holds a non-finite position");
  EXPECT_THROW(read_micmac_homol_folder(dir + "/nothing"), InputError);
}
