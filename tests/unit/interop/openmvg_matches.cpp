// OpenMVG regions and matches files: layout, round trip (float32 positions, names, counts), bad input.
#include "tpkit/interop/openmvg_matches.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "sample_matches.hpp"
#include "tpkit/core/error.hpp"

using namespace tpkit;
using tpkit_test::f32;

namespace {
std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
}  // namespace

TEST(OpenmvgMatches, LayoutAndRoundTrip) {
  const std::string dir = tpkit_test::scratch_dir("openmvg");
  const Matches ab = tpkit_test::sample_matches("/d/A.tif", "/d/B.png", 6, 11);
  const Matches cb = tpkit_test::sample_matches("/d/C.tif", "/d/B.png", 4, 12);
  write_openmvg(dir, collect_peer_keypoints({ab, cb}));
  // C (view 2) -> B (view 1) is written "1 2" with B's index first
  const std::string list = slurp(dir + "/matches.f.txt");
  EXPECT_EQ(list.substr(0, 8), "0 1\n6\n0 ");
  EXPECT_NE(list.find("1 2\n4\n6 0\n"), std::string::npos) << list;
  std::istringstream feat(slurp(dir + "/A.feat"));
  double x, y, scale, orientation;
  feat >> x >> y >> scale >> orientation;
  EXPECT_EQ(static_cast<float>(x), f32(ab.xy(0, 0)));
  EXPECT_EQ(scale, 1);
  EXPECT_EQ(orientation, 0);
  EXPECT_NE(slurp(dir + "/sfm_data.json").find("\"filename\": \"B.png\""), std::string::npos);

  const std::vector<Matches> back = read_openmvg(dir + "/matches.f.txt");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].image1.path, "A.tif");
  EXPECT_EQ(back[0].image2.path, "B.png");
  EXPECT_EQ(back[0].image2.height, 1040);
  EXPECT_EQ(back[1].image1.path, "B.png");
  EXPECT_EQ(meta_get(back[0].meta, "source-format"), "openmvg");
  ASSERT_EQ(back[0].size(), 6u);
  ASSERT_EQ(back[1].size(), 4u);
  for (size_t r = 0; r < 6; ++r) {
    for (int c = 0; c < 4; ++c) EXPECT_EQ(back[0].xy(r, c), f32(ab.xy(r, c)));
    EXPECT_EQ(back[0].id1[r], static_cast<long long>(r));  // the keypoint index
  }
  for (size_t r = 0; r < 4; ++r) {
    EXPECT_EQ(back[1].xy(r, 0), f32(cb.xy(r, 2)));
    EXPECT_EQ(back[1].xy(r, 2), f32(cb.xy(r, 0)));
    EXPECT_EQ(back[1].id1[r], static_cast<long long>(6 + r));  // B's entries after those of pair A-B
  }
}

TEST(OpenmvgMatches, ViewsFromImagesWithoutSfmData) {
  const std::string dir = tpkit_test::scratch_dir("openmvg-images");
  std::ofstream(dir + "/a.feat") << "1.5 2.5 1 0\n3 4 1 0\n";
  std::ofstream(dir + "/b.feat") << "10 20 0.5 0.1\n";
  std::ofstream(dir + "/matches.putative.txt") << "0 1\n2\n0 0\n1 0\n";
  EXPECT_THROW(read_openmvg(dir + "/matches.putative.txt"), InputError);
  const auto back = read_openmvg(dir + "/matches.putative.txt", {"a.png", "b.png"});
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].xy(1, 0), 3);
  EXPECT_EQ(back[0].xy(1, 2), 10);
}

TEST(OpenmvgMatches, BadInput) {
  const std::string dir = tpkit_test::scratch_dir("openmvg-bad");
  std::ofstream(dir + "/a.feat") << "1 2 1 0\n";
  std::ofstream(dir + "/b.feat") << "1 2 1 0\n";
  auto fails_with = [&](const std::string& text, const std::string& what) {
    const std::string path = dir + "/matches.f.txt";
    std::ofstream(path) << text;
    tpkit_test::expect_input_error([&] { read_openmvg(path, {"a", "b"}); }, path, what);
  };
  fails_with("0 1\n3\n0 0\n", "truncated");
  fails_with("0 1\n1\n0 5\n", "beyond the .feat file");
  fails_with("0 7\n1\n0 0\n", "names no image");
  fails_with("0 1 2\n", "two view ids");
  fails_with("0 1\nx\n", "not an index");
}

// sfm_data.json read as JSON (issue 23: a std::regex scan recursed per character and crashed on a view
// whose "data" object held 300 000 characters); one id names one view.
TEST(OpenmvgMatches, SfmDataAsJson) {
  const std::string dir = tpkit_test::scratch_dir("openmvg-json");
  std::ofstream(dir + "/a.feat") << "1 2 1 0\n";
  std::ofstream(dir + "/b.feat") << "3 4 1 0\n";
  std::ofstream(dir + "/matches.f.txt") << "0 1\n1\n0 0\n";
  auto view = [](int id, const std::string& name, const std::string& extra) {
    return "{\"key\": " + std::to_string(id) + ", \"value\": {\"polymorphic_id\": 1073741824, \"ptr_wrapper\": {\"id\": " +
           std::to_string(2147483649 + id) + ", \"data\": {" + extra + "\"local_path\": \"\", \"filename\": \"" + name +
           "\", \"width\": 100, \"height\": 80, \"id_view\": " + std::to_string(id) + ", \"id_intrinsic\": 0, \"id_pose\": " +
           std::to_string(id) + "}}}}";
  };
  auto sfm = [&](const std::string& views) {
    std::ofstream(dir + "/sfm_data.json") << "{\"sfm_data_version\": \"0.3\", \"root_path\": \"\", \"views\": [" << views
                                          << "], \"intrinsics\": [], \"extrinsics\": []}\n";
  };
  const std::string long_field = "\"note\": \"" + std::string(300000, 'x') + "\", ";
  sfm(view(0, "a.tif", long_field) + ", " + view(1, "b.tif", ""));
  const auto ms = read_openmvg(dir + "/matches.f.txt");
  ASSERT_EQ(ms.size(), 1u);
  EXPECT_EQ(ms[0].image1.path, "a.tif");
  EXPECT_EQ(ms[0].image2.width, 100);
  EXPECT_DOUBLE_EQ(ms[0].xy(0, 2), 3);
  sfm(view(0, "a.tif", "") + ", " + view(0, "b.tif", ""));
  tpkit_test::expect_input_error([&] { read_openmvg(dir + "/matches.f.txt"); }, dir + "/sfm_data.json", "view id 0 is also that of a.tif");
  sfm(view(0, "a.tif", "") + ", {\"key\": 1");
  tpkit_test::expect_input_error([&] { read_openmvg(dir + "/matches.f.txt"); }, dir + "/sfm_data.json", "not valid JSON");
}
