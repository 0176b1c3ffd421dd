// GCP files: ASP's .gcp and tpkit's gcp kind read to one form (lon, lat, h; sigmas east, north, up in
// metres; tpkit pixels), written and read back, and bad lines refused with file:line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "tpkit/core/error.hpp"
#include "tpkit/ground/gcp_file.hpp"

using namespace tpkit;

namespace {
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(GcpFile, AspLinesBecomeLonLatAndEastNorthSigmas) {
  const std::string text =
      "# WKT: GEOGCS[\"WGS 84\"]\n"
      "\n"
      "3, 43.25, 5.375, 120.5, 0.5, 0.5, 0.5, a.tif, 10.5, 20.25, 0.2, 0.3 dir/b.tif 30 40 0.1 0.1\n"
      "4 0 0 10 1 2 3\n";
  const auto g = parse_asp_gcp(text, "x.gcp");
  ASSERT_EQ(g.size(), 2u);
  EXPECT_EQ(g[0].id, 3);
  EXPECT_EQ(g[0].line, 3);
  EXPECT_EQ(g[0].role, GcpRole::control);
  EXPECT_EQ(g[0].llh, Eigen::Vector3d(5.375, 43.25, 120.5));  // lat lon swapped to lon lat
  EXPECT_TRUE(g[0].sigma_enu.isApprox(Eigen::Vector3d::Constant(0.5), 1e-12));  // equal ECEF sigmas: the same in ENU
  // at lon 0, lat 0: east is ECEF y, north z, up x
  EXPECT_TRUE(g[1].sigma_enu.isApprox(Eigen::Vector3d(2, 3, 1), 1e-12));
  ASSERT_EQ(g[0].measurements.size(), 2u);
  EXPECT_EQ(g[0].measurements[0].image, "a.tif");
  EXPECT_EQ(g[0].measurements[0].xy, Eigen::Vector2d(10.5, 20.25));  // ASP's pixel convention is tpkit's
  EXPECT_EQ(g[0].measurements[0].sigma_px, 0.3);                     // the larger of the two
  EXPECT_EQ(g[0].measurements[1].image, "dir/b.tif");
  EXPECT_TRUE(g[1].measurements.empty());
}

TEST(GcpFile, BadAspLinesNameFileAndLine) {
  EXPECT_NE(error_of([] { parse_asp_gcp("1 43 5 100 1 1 1 a.tif 1 2 0.2\n", "x.gcp"); }).find("x.gcp:1:"), std::string::npos);
  EXPECT_NE(error_of([] { parse_asp_gcp("# c\n1 43 5 100 1 0 1\n", "x.gcp"); }).find("x.gcp:2:"), std::string::npos);
  EXPECT_NE(error_of([] { parse_asp_gcp("1 93 5 100 1 1 1\n", "x.gcp"); }).find("x.gcp:1:"), std::string::npos);
  EXPECT_NE(error_of([] { parse_asp_gcp("1 43 5 1OO 1 1 1\n", "x.gcp"); }).find("x.gcp:1: height"), std::string::npos);
  EXPECT_NE(error_of([] { parse_asp_gcp("1 43 5 100 1 1 1\n1 43 5 100 1 1 1\n", "x.gcp"); }).find("x.gcp:2:"), std::string::npos);
  EXPECT_NE(error_of([] { parse_asp_gcp("1 43 5 100 1 1 1 a.tif 1 2 0 0.2\n", "x.gcp"); }).find("x.gcp:1:"), std::string::npos);
}

TEST(GcpFile, TpkitFormRoundTripsWithRoles) {
  Gcp a;
  a.id = 7;
  a.llh = {5.4, 43.3, 150.25};
  a.sigma_enu = {0.3, 0.4, 0.5};
  a.measurements = {{"v1.tif", {1.5, 2.5}, 0.2, 0}, {"v2.tif", {3, 4}, 0.25, 0}};
  Gcp b = a;
  b.id = 8;
  b.role = GcpRole::check;
  b.measurements = {{"v2.tif", {5, 6}, 0.2, 0}};
  Gcp c = a;
  c.id = 9;
  c.measurements.clear();
  const std::string text = format_tpkit_gcp({a, b, c});
  const auto g = parse_tpkit_gcp(text, "p.gcp");
  ASSERT_EQ(g.size(), 3u);
  EXPECT_EQ(g[0].llh, a.llh);
  EXPECT_EQ(g[0].sigma_enu, a.sigma_enu);
  ASSERT_EQ(g[0].measurements.size(), 2u);
  EXPECT_EQ(g[0].measurements[1].image, "v2.tif");
  EXPECT_EQ(g[0].measurements[1].xy, Eigen::Vector2d(3, 4));
  EXPECT_EQ(g[0].measurements[1].sigma_px, 0.25);
  EXPECT_EQ(g[1].role, GcpRole::check);
  EXPECT_EQ(g[1].measurements[0].image, "v2.tif");
  EXPECT_TRUE(g[2].measurements.empty());
  // read_gcp_file tells the forms apart by the first line
  const auto path = std::filesystem::temp_directory_path() / ("tpkit-gcp-file-test-" + std::to_string(::getpid()) + ".gcp");
  std::ofstream(path) << text;
  EXPECT_EQ(read_gcp_file(path.string()).size(), 3u);
  std::ofstream(path) << "5 43 5 100 1 1 1\n";
  EXPECT_EQ(read_gcp_file(path.string())[0].id, 5);
  std::filesystem::remove(path);
}

TEST(GcpFile, BadTpkitRecordsNameFileAndLine) {
  const std::string head = "# tpkit gcp 1\n# image1: v1.tif 10 10\n# columns: id role lon lat h sigma_e sigma_n sigma_u image x y sigma_px\n";
  EXPECT_NE(error_of([&] { parse_tpkit_gcp(head + "1 2 5 43 100 1 1 1 1 3 4 0.2\n", "t.gcp"); }).find("t.gcp:4: role"), std::string::npos);
  EXPECT_NE(error_of([&] { parse_tpkit_gcp(head + "1 0 5 43 100 1 1 1 2 3 4 0.2\n", "t.gcp"); }).find("t.gcp:4: image 2"), std::string::npos);
  EXPECT_NE(error_of([&] { parse_tpkit_gcp(head + "1 0 5 43 100 1 1 1 1 3 4 0.2\n1 0 5 43 101 1 1 1 1 3 4 0.2\n", "t.gcp"); })
                .find("t.gcp:5:"),
            std::string::npos);
  EXPECT_NE(error_of([&] { parse_tpkit_gcp(head + "1 0 5 43 100 1 1 1 1 3 4 0.2\n1 0 5 43 100 1 1 1 1 5 6 0.2\n", "t.gcp"); })
                .find("twice"),
            std::string::npos);
}

// Issue 50, items 9 and 17: a UTF-8 byte order mark is skipped (it made the first id unreadable), an id
// beyond 2^53 is refused with file:line (a double, which every tpkit table holds, would round it), a file
// given twice (by any name) and an id in two files are refused (each counted its points twice).
TEST(GcpFile, ByteOrderMarkIdsBeyondDoublesAndFilesGivenTwice) {
  const auto dir = std::filesystem::temp_directory_path() / ("gcp-file-test-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string a = (dir / "a.gcp").string(), b = (dir / "b.gcp").string(), link = (dir / "link.gcp").string();
  std::ofstream(a) << "\xEF\xBB\xBF" "1 43.3 5.4 100 1 1 1 v.tif 10 20 0.2 0.2\n2 43.3 5.4 100 1 1 1\n";
  std::ofstream(b) << "\xEF\xBB\xBF# tpkit gcp 1\n# columns: id role lon lat h sigma_e sigma_n sigma_u image x y sigma_px\n"
                      "2 0 5.4 43.3 100 1 1 1 0 nan nan nan\n";
  std::filesystem::remove(link);
  std::filesystem::create_symlink(a, link);
  const auto g = read_gcp_file(a);
  ASSERT_EQ(g.size(), 2u);
  EXPECT_EQ(g[0].id, 1);
  ASSERT_EQ(read_gcp_file(b).size(), 1u);  // the BOM before "# tpkit gcp" hid the form
  EXPECT_EQ(read_gcp_files({a}).size(), 2u);
  EXPECT_NE(error_of([&] { read_gcp_files({a, a}); }).find(a + ": given twice"), std::string::npos);
  EXPECT_NE(error_of([&] { read_gcp_files({a, link}); }).find(link + ": given twice (also as " + a + ")"), std::string::npos);
  EXPECT_NE(error_of([&] { read_gcp_files({a, b}); }).find(b + ":3: point 2 is also " + a + ":2"), std::string::npos);
  EXPECT_NE(error_of([] { parse_asp_gcp("12345678901234567890 43 5 100 1 1 1\n", "x.gcp"); }).find("x.gcp:1: id '12345678901234567890' is beyond 2^53"),
            std::string::npos);
  EXPECT_EQ(parse_asp_gcp("9007199254740992 43 5 100 1 1 1\n", "x.gcp")[0].id, 9007199254740992LL);
  EXPECT_NE(error_of([] {
              parse_tpkit_gcp("# tpkit gcp 1\n# columns: id role lon lat h sigma_e sigma_n sigma_u image x y sigma_px\n"
                              "1e19 0 5.4 43.3 100 1 1 1 0 nan nan nan\n", "t.gcp");
            }).find("t.gcp:3: id '1e+19' is beyond 2^53"),
            std::string::npos);
  std::filesystem::remove_all(dir);
}
