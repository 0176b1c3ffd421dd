// COLMAP database and text form: the schema of COLMAP 3.8, the 0.5 pixel offset, pair ids, blobs and
// F pinned; round trips with ids; bad databases.
#include "tpkit/interop/colmap_database.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <Eigen/Geometry>
#include <random>
#include <set>

#include "sample_matches.hpp"
#include "tpkit/core/error.hpp"

using namespace tpkit;
using tpkit_test::f32;

namespace {

struct Sql {
  sqlite3* db = nullptr;
  explicit Sql(const std::string& path) { EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK); }
  ~Sql() { sqlite3_close(db); }
  // first row of a query, each column as text (blobs as raw bytes)
  std::vector<std::string> row(const std::string& q) {
    sqlite3_stmt* s = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db, q.c_str(), -1, &s, nullptr), SQLITE_OK) << q;
    std::vector<std::string> out;
    if (sqlite3_step(s) == SQLITE_ROW)
      for (int c = 0; c < sqlite3_column_count(s); ++c)
        out.emplace_back(static_cast<const char*>(sqlite3_column_blob(s, c)) ? static_cast<const char*>(sqlite3_column_blob(s, c)) : "",
                         static_cast<size_t>(sqlite3_column_bytes(s, c)));
    sqlite3_finalize(s);
    return out;
  }
};

template <class T>
T at(const std::string& blob, size_t i) {
  T v;
  std::memcpy(&v, blob.data() + i * sizeof(T), sizeof(T));
  return v;
}

}  // namespace

TEST(ColmapDatabase, PairId) {
  EXPECT_EQ(colmap_pair_id(1, 2), 2147483649LL);
  EXPECT_EQ(colmap_pair_id(3, 1), 2147483650LL);
  EXPECT_EQ(colmap_pair_id(2, 3), 4294967297LL);
}

TEST(ColmapDatabase, SchemaBlobsOffsetAndF) {
  const std::string dir = tpkit_test::scratch_dir("colmap");
  // image order given: B is image 1, so the file A->B is stored swapped (B's keypoints first)
  const Matches m = tpkit_test::sample_matches("A.tif", "B.tif", 30, 7);
  const PeerKeypoints k = collect_peer_keypoints({m}, {"B.tif"});
  const std::string db = dir + "/database.db";
  write_colmap_database(db, k);
  Sql s(db);
  // the tables of colmap database_creator (3.8), and ours
  std::set<std::string> tables;
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(s.db, "SELECT name FROM sqlite_master WHERE type='table'", -1, &st, nullptr);
  while (sqlite3_step(st) == SQLITE_ROW) tables.insert(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)));
  sqlite3_finalize(st);
  EXPECT_EQ(tables, (std::set<std::string>{"cameras", "sqlite_sequence", "images", "keypoints", "descriptors", "matches",
                                           "two_view_geometries", "tpkit_keypoint_ids"}));
  EXPECT_EQ(s.row("SELECT name, camera_id FROM images WHERE image_id = 1"), (std::vector<std::string>{"B.tif", "1"}));
  EXPECT_EQ(s.row("SELECT model, width, height, prior_focal_length FROM cameras WHERE camera_id = 2"),
            (std::vector<std::string>{"0", "1024", "1000", "0"}));
  const auto params = s.row("SELECT params FROM cameras WHERE camera_id = 2")[0];
  ASSERT_EQ(params.size(), 24u);
  EXPECT_EQ(at<double>(params, 0), 1.2 * 1024);
  EXPECT_EQ(at<double>(params, 1), 512);
  EXPECT_EQ(at<double>(params, 2), 500);
  // keypoints of A (image_id 2): its first entry is record 0's (x1, y1) + 0.5, float32
  const auto kp = s.row("SELECT rows, cols, data FROM keypoints WHERE image_id = 2");
  EXPECT_EQ(kp[0], "30");
  EXPECT_EQ(kp[1], "2");
  EXPECT_EQ(at<float>(kp[2], 0), f32(m.xy(0, 0) + 0.5));
  EXPECT_EQ(at<float>(kp[2], 1), f32(m.xy(0, 1) + 0.5));
  // B: 30 records, id 5 at two positions -> 30 entries; ids kept in tpkit_keypoint_ids
  const auto ids = s.row("SELECT rows, data FROM tpkit_keypoint_ids WHERE image_id = 1");
  EXPECT_EQ(ids[0], "30");
  EXPECT_EQ(at<int64_t>(ids[1], 1), 5);
  // pair_id of (1, 2); data: B's index first (swapped)
  const auto mt = s.row("SELECT pair_id, rows, cols, data FROM matches");
  EXPECT_EQ(mt[0], "2147483649");
  EXPECT_EQ(mt[1], "30");
  EXPECT_EQ(mt[2], "2");
  EXPECT_EQ(at<uint32_t>(mt[3], 2 * 29), 29u);      // record 29 is B's entry 29 ...
  EXPECT_EQ(at<uint32_t>(mt[3], 2 * 29 + 1), 29u);  // ... and A's entry 29
  const auto tv = s.row("SELECT config, F, length(F) FROM two_view_geometries WHERE pair_id = 2147483649");
  EXPECT_EQ(tv[0], "3");
  EXPECT_EQ(tv[2], "72");
  // F row-major, from the pair in COLMAP pixels with image 1 = the smaller id = B: x_A^T F x_B = 0
  Eigen::MatrixX4d colmap_xy(30, 4);
  for (int r = 0; r < 30; ++r)
    colmap_xy.row(r) << f32(m.xy(r, 2) + 0.5), f32(m.xy(r, 3) + 0.5), f32(m.xy(r, 0) + 0.5), f32(m.xy(r, 1) + 0.5);
  const Eigen::Matrix3d F = fundamental_8point(colmap_xy);
  for (int i = 0; i < 9; ++i) EXPECT_EQ(at<double>(tv[1], i), F(i / 3, i % 3)) << i;
}

TEST(ColmapDatabase, EightPointOnExactCorrespondences) {
  // two pinhole views of random points in front of both: every point lies on its epipolar line
  const Eigen::Matrix3d K = (Eigen::Matrix3d() << 1000, 0, 512, 0, 1000, 512, 0, 0, 1).finished();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(-1, 0.1, 0.05);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixX4d xy(30, 4);
  for (int r = 0; r < 30; ++r) {
    const Eigen::Vector3d X(u(rng), u(rng), 5 + u(rng));
    const Eigen::Vector3d a = K * X, b = K * (R * X + t);
    xy.row(r) << a.x() / a.z(), a.y() / a.z(), b.x() / b.z(), b.y() / b.z();
  }
  const Eigen::Matrix3d F = fundamental_8point(xy);
  for (int r = 0; r < 30; ++r) {
    const Eigen::Vector3d a(xy(r, 0), xy(r, 1), 1), b(xy(r, 2), xy(r, 3), 1);
    EXPECT_NEAR(b.dot(F * a) / (F * a).head<2>().norm(), 0.0, 1e-6);  // distance to the epipolar line, px
  }
  EXPECT_NEAR(F.norm(), 1.0, 1e-12);
  EXPECT_NEAR(F.determinant(), 0.0, 1e-12);
}

TEST(ColmapDatabase, RoundTripKeepsIdsNamesCountsToFloat32) {
  const std::string dir = tpkit_test::scratch_dir("colmap-rt");
  const Matches ab = tpkit_test::sample_matches("/d/A.tif", "/d/B.tif", 25, 8);
  const Matches cb = tpkit_test::sample_matches("/d/C.tif", "/d/B.tif", 12, 9);
  write_colmap_database(dir + "/database.db", collect_peer_keypoints({ab, cb}));
  for (bool verified : {true, false}) {
    const std::vector<Matches> back = read_colmap_database(dir + "/database.db", verified);
    ASSERT_EQ(back.size(), 2u);
    // pairs ordered by pair_id: (1=A, 2=B), then (2=B, 3=C): the second is cb swapped
    EXPECT_EQ(back[0].image1.path, "A.tif");
    EXPECT_EQ(back[0].image2.width, 1028);
    EXPECT_EQ(back[1].image1.path, "B.tif");
    EXPECT_EQ(meta_get(back[0].meta, "source-format"), verified ? "colmap" : "colmap-raw");
    EXPECT_EQ(meta_get(back[1].meta, "keypoints"), "37 12");
    ASSERT_EQ(back[0].size(), ab.size());
    ASSERT_EQ(back[1].size(), cb.size());
    for (size_t r = 0; r < ab.size(); ++r) {
      EXPECT_EQ(back[0].id1[r], ab.id1[r]);
      EXPECT_EQ(back[0].id2[r], ab.id2[r]);
      for (int c = 0; c < 4; ++c) EXPECT_NEAR(back[0].xy(r, c), f32(ab.xy(r, c) + 0.5) - 0.5, 0) << r << c;
    }
    for (size_t r = 0; r < cb.size(); ++r) {
      EXPECT_EQ(back[1].id1[r], cb.id2[r]);
      EXPECT_EQ(back[1].xy(r, 0), f32(cb.xy(r, 2) + 0.5) - 0.5);
      EXPECT_EQ(back[1].xy(r, 3), f32(cb.xy(r, 1) + 0.5) - 0.5);
    }
  }
}

TEST(ColmapDatabase, TextImportForm) {
  const std::string dir = tpkit_test::scratch_dir("colmap-txt");
  const Matches m = tpkit_test::sample_matches("/d/A.tif", "B.tif", 3, 10);
  write_colmap_text(dir, collect_peer_keypoints({m}));
  std::ifstream kp(dir + "/keypoints/A.tif.txt");
  std::string head;
  std::getline(kp, head);
  EXPECT_EQ(head, "3 128");
  double x, y, scale, orientation;
  kp >> x >> y >> scale >> orientation;
  EXPECT_EQ(static_cast<float>(x), f32(m.xy(0, 0) + 0.5));
  EXPECT_EQ(scale, 1);
  std::ifstream list(dir + "/matches.txt");
  std::string l1, l2, l3, l4, l5;
  std::getline(list, l1);
  std::getline(list, l2);
  std::getline(list, l3);
  std::getline(list, l4);
  std::getline(list, l5);
  EXPECT_EQ(l1, "A.tif B.tif");
  EXPECT_EQ(l2, "0 0");
  EXPECT_EQ(l4, "2 2");
  EXPECT_EQ(l5, "");
}

TEST(ColmapDatabase, BadDatabases) {
  const std::string dir = tpkit_test::scratch_dir("colmap-bad");
  auto fails_with = [&](const std::string& path, const std::string& what) {
    tpkit_test::expect_input_error([&] { read_colmap_database(path, true); }, path, what);
  };
  {
    Sql s(dir + "/empty.db");
    sqlite3_exec(s.db, "CREATE TABLE other (a INTEGER)", nullptr, nullptr, nullptr);
  }
  fails_with(dir + "/empty.db", "no table 'cameras'");
  std::ofstream(dir + "/text.db") << "not a database at all, just text that is long enough to have a header\n";
  fails_with(dir + "/text.db", "not a database");
  fails_with(dir + "/missing.db", "no such database file");
  // a keypoint blob shorter than rows x cols says
  write_colmap_database(dir + "/short.db", collect_peer_keypoints({tpkit_test::sample_matches("A", "B", 10, 1)}));
  {
    Sql s(dir + "/short.db");
    sqlite3_exec(s.db, "UPDATE keypoints SET rows = 11 WHERE image_id = 1", nullptr, nullptr, nullptr);
  }
  fails_with(dir + "/short.db", "the blob holds 80 bytes, rows x cols say 11 x 2 values");
  // an image without a size cannot become a COLMAP camera
  Matches nosize = tpkit_test::sample_matches("A", "B", 10, 1);
  nosize.image1.width = 0;
  EXPECT_THROW(write_colmap_database(dir + "/nosize.db", collect_peer_keypoints({nosize})), InputError);
  EXPECT_FALSE(std::filesystem::exists(dir + "/nosize.db"));
}

// What an outside hostile-input campaign fed the reader (issue 23): each database is a good one with one
// field forged. Before: a rows x cols product that overflowed to the blob's size read past it (SIGSEGV);
// NaN keypoints, names that break a header, a pair of an image with itself, a pair id with the larger
// image first and tpkit ids that join unrelated points were all taken.
TEST(ColmapDatabase, HostileDatabases) {
  const std::string dir = tpkit_test::scratch_dir("colmap-hostile");
  const PeerKeypoints good = collect_peer_keypoints({tpkit_test::sample_matches("A", "B", 10, 1)});
  auto forged = [&](const std::string& name, const std::string& sql) {
    const std::string path = dir + "/" + name + ".db";
    write_colmap_database(path, good);
    Sql s(path);
    char* err = nullptr;
    EXPECT_EQ(sqlite3_exec(s.db, sql.c_str(), nullptr, nullptr, &err), SQLITE_OK) << (err ? err : "") << ": " << sql;
    sqlite3_free(err);
    return path;
  };
  auto fails_with = [&](const std::string& path, const std::string& what) {
    tpkit_test::expect_input_error([&] { read_colmap_database(path, true); }, path, what);
  };
  fails_with(forged("overflow", "UPDATE keypoints SET rows = 4611686018427387905, cols = 4, data = zeroblob(16) WHERE image_id = 1"),
             "the blob holds 16 bytes, rows x cols say 4611686018427387905 x 4 values");
  fails_with(forged("negative", "UPDATE keypoints SET rows = -1 WHERE image_id = 1"), "negative rows or cols");
  fails_with(forged("nan", "UPDATE keypoints SET data = X'0000C07F' || substr(data, 5) WHERE image_id = 1"),
             "keypoints of image_id 1: keypoint 0 is not finite");
  fails_with(forged("inf", "UPDATE keypoints SET data = substr(data, 1, 4) || X'0000807F' || substr(data, 9) WHERE image_id = 2"),
             "keypoints of image_id 2: keypoint 0 is not finite");
  fails_with(forged("newline", "UPDATE images SET name = 'A' || char(10) || '# image2: x' WHERE image_id = 1"),
             "holds a line break or another control character");
  fails_with(forged("empty-name", "UPDATE images SET name = '' WHERE image_id = 2"), "names an image with an empty name");
  fails_with(forged("self", "UPDATE two_view_geometries SET pair_id = 2147483647 + 1"), "pairs image_id 1 with itself");
  fails_with(forged("larger-first", "UPDATE two_view_geometries SET pair_id = 2 * 2147483647 + 1"),
             "is not a COLMAP pair id: it decodes to image_id 2 then 1");
  fails_with(forged("ids-equal", "UPDATE tpkit_keypoint_ids SET data = zeroblob(length(data))"),
             "tpkit_keypoint_ids give one id to two positions in both images");
  // issue 50: all ids of one image equal, its positions far apart: not one keypoint refined per match
  fails_with(forged("ids-equal-one-image", "UPDATE tpkit_keypoint_ids SET data = zeroblob(length(data)) WHERE image_id = 2"),
             "pair_id 2147483649: tpkit_keypoint_ids give id 0 of image_id 2 two positions more than 10 px apart (matches 0 and 1)");
  // the good one still reads
  EXPECT_EQ(read_colmap_database(forged("good", "SELECT 1"), true).at(0).size(), 10u);
}
