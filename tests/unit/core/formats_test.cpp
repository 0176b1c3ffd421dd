// Round trips and rejections of every file kind, and atomic writing.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {
fs::path scratch(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("tpkit-formats-test-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d / name;
}
std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}
}  // namespace

TEST(Formats, TracksRoundTrip) {
  Tracks t;
  t.images = {{"v1.tif", 100, 200}, {"v2.tif", 100, 200}, {"v3.tif", 100, 200}};
  meta_set(t.meta, "source", "unit test");
  t.xy.resize(2, 6);
  t.xy << 1.25, 2.5, 3, 4, 5, 6, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6;
  t.id = {7, 9};
  t.extra.names = {"X"};
  t.extra.values.resize(2, 1);
  t.extra.values << 100.5, -3;
  auto p = scratch("a.tracks");
  save_tracks(p.string(), t);
  std::string text = slurp(p);
  EXPECT_EQ(text.rfind("# tpkit tracks 1\n# written-by: ", 0), 0u) << text;
  EXPECT_NE(text.find("\n# image1: v1.tif 100 200\n"), std::string::npos) << text;
  EXPECT_NE(text.find("# columns: track x1 y1 x2 y2 x3 y3 X\n7 1.25 2.5 3 4 5 6 100.5\n"), std::string::npos);
  auto r = read_tracks(p.string());
  EXPECT_EQ(r.views(), 3);
  EXPECT_EQ(r.images[2].path, "v3.tif");
  EXPECT_EQ(r.id[1], 9);
  EXPECT_TRUE(r.xy.isApprox(t.xy, 0));
  EXPECT_EQ(meta_get(r.meta, "source"), "unit test");
  EXPECT_EQ(r.extra.values(0, 0), 100.5);
  EXPECT_EQ(r.line[1], 9);  // header: kind, writer, 3 images, 1 meta, columns; records on lines 8 and 9
}

// Issue 24: a view a track is not seen in is "nan nan"; such a file is version 2, reads back with the
// same NaNs, and its complete tracks can be selected.
TEST(Formats, TracksWithViewsNotSeen) {
  const std::string text =
      "# tpkit tracks 2\n# image1: a 10 10\n# image2: b 10 10\n# image3: c 10 10\n"
      "# columns: track x1 y1 x2 y2 x3 y3 sigma1 sigma2 sigma3\n"
      "0 1 2 3 4 5 6 0.1 0.1 0.2\n1 nan nan 3 4 5 6 nan 0.1 0.2\n2 1 2 nan nan 5.5 6.5 0.1 nan 0.1\n";
  std::istringstream in(text);
  Tracks t = tracks_from_table(read_table(in, "t", tracks_read_options()));
  ASSERT_EQ(t.size(), 3u);
  EXPECT_FALSE(t.complete());
  EXPECT_TRUE(t.seen(0, 0));
  EXPECT_FALSE(t.seen(1, 0));
  EXPECT_FALSE(t.seen(2, 1));
  EXPECT_EQ(t.seen_views(1), 2);
  EXPECT_TRUE(std::isnan(t.extra.values(1, 0)));
  std::ostringstream out;
  write_tracks(out, t);
  EXPECT_NE(out.str().find("# tpkit tracks 2\n"), std::string::npos);
  EXPECT_NE(out.str().find("\n1 nan nan 3 4 5 6 nan 0.1 0.2\n"), std::string::npos);
  size_t left = 0;
  Tracks all = tracks_seen_in_all_views(t, &left);
  EXPECT_EQ(left, 2u);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all.id[0], 0);
  EXPECT_EQ(all.xy(0, 5), 6);
  EXPECT_EQ(all.extra.values(0, 2), 0.2);
  // complete tracks are still written as version 1
  std::ostringstream out1;
  write_tracks(out1, all);
  EXPECT_EQ(out1.str().rfind("# tpkit tracks 1\n", 0), 0u);
  auto refused = [](const std::string& body) {
    std::istringstream s("# tpkit tracks 2\n# columns: track x1 y1 x2 y2 x3 y3 kp\n" + body);
    try {
      tracks_from_table(read_table(s, "t", tracks_read_options()));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refused("0 nan 2 3 4 5 6 1\n"), "t:3: view 1 has x1 nan and y1 a number: a view not seen is nan in both columns");
  EXPECT_EQ(refused("0 nan nan nan nan 5 6 1\n"), "t:3: track seen in 1 view: a track needs two or more");
  EXPECT_EQ(refused("0 1 2 3 4 5 6 nan\n"), "t:3: field 'kp' is not finite: 'nan'");  // only view columns may be nan
  EXPECT_EQ(refused("0 1 2 inf 4 5 6 1\n"), "t:3: field 'x2' is not finite: 'inf'");
  // nan stays an error in every other kind
  std::istringstream m("# tpkit matches 1\n# columns: id1 x1 y1 id2 x2 y2\n1 nan nan 2 3 4\n");
  EXPECT_THROW(matches_from_table(read_table(m, "m", matches_read_options())), InputError);
}

TEST(Formats, TrifocalNormalizedAndRoundTrip) {
  Trifocal t;
  for (int i = 0; i < 3; ++i) t.T[i] = Eigen::Matrix3d::Random() * (i + 1);
  t.T[2](1, 1) = -50;  // largest entry negative: the writer flips the sign
  meta_set(t.meta, "method", "test");
  auto p = scratch("a.trifocal");
  save_trifocal(p.string(), t);
  auto r = read_trifocal(p.string());
  double n2 = 0;
  for (int i = 0; i < 3; ++i) n2 += r.T[i].squaredNorm();
  EXPECT_NEAR(n2, 1, 1e-15);
  EXPECT_GT(r.T[2](1, 1), 0);
  double s = r.T[2](1, 1) / t.T[2](1, 1);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE((t.T[i] * s).isApprox(r.T[i], 1e-15));
  EXPECT_EQ(meta_get(r.meta, "method"), "test");
}

TEST(Formats, HomographyAndCamerasRoundTrip) {
  Homography h;
  h.H << 1, 2, 3, 4, 5, 6, 7, 8, 10;
  auto ph = scratch("a.homography");
  save_homography(ph.string(), h);
  EXPECT_TRUE(read_homography(ph.string()).H.isApprox(h.H, 0));
  Cameras c;
  c.P.resize(3);
  for (auto& P : c.P) P.setRandom();
  auto pc = scratch("a.cameras");
  save_cameras(pc.string(), c);
  auto rc = read_cameras(pc.string());
  ASSERT_EQ(rc.P.size(), 3u);
  for (int v = 0; v < 3; ++v) EXPECT_TRUE(rc.P[v].isApprox(c.P[v], 0));
}

TEST(Formats, MatrixKindsRejectBadShapes) {
  auto bad = [](const std::string& text, auto reader) {
    auto p = scratch("bad.txt");
    { std::ofstream(p) << text; }
    try {
      reader(p.string());
    } catch (const InputError& e) {
      return std::string(e.what()).substr(p.string().size());
    }
    return std::string("no error");
  };
  EXPECT_EQ(bad("# tpkit trifocal 1\n1 2 3 4 5 6 7 8 9\n1 2 3 4 5 6 7 8 9\n", read_trifocal),
            ": a trifocal file holds three records (T_1, T_2, T_3); found 2 records");
  EXPECT_EQ(bad("# tpkit trifocal 1\n1 2 3 4 5 6 7 8\n", read_trifocal), ":2: expected 9 numbers (T_i row-major), found 8");
  EXPECT_EQ(bad("# tpkit homography 1\n1 0 0\n0 1 0\n0 0 1\n0 0 1\n", read_homography),
            ":5: a homography file holds three records (the rows of H); found 4 records");
  EXPECT_EQ(bad("# tpkit homography 1\n1 0 0\n2 0 0\n0 0 0\n", read_homography), ":2: the homography is singular");
  EXPECT_EQ(bad("# tpkit cameras 1\n1 0 0 0\n0 1 0 0\n0 0 0 1\n", read_cameras),
            ":2: camera 1 has no '# view 1' line");
  EXPECT_EQ(bad("# tpkit points 1\n# columns: x y\n1 2\n3\n", read_points), ":4: missing column 'y' (1 fields, 2 columns)");
  EXPECT_EQ(bad("# tpkit homography 1\n1 0 0\n0 1 0\n0 0 1\n", read_trifocal),
            ":1: wrong header kind: expected 'trifocal', found 'homography'");
}

TEST(Formats, AtomicOutputLeavesNoFileOnFailure) {
  auto p = scratch("never.txt");
  fs::remove(p);
  try {
    AtomicOutput out(p.string());
    out.stream() << "half of it";
    throw std::runtime_error("fail midway");
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(fs::exists(p));
  for (auto& e : fs::directory_iterator(p.parent_path()))
    EXPECT_EQ(e.path().filename().string().find("never.txt.tmp"), std::string::npos) << e.path();
  // an existing file is replaced only on commit
  { std::ofstream(p) << "old"; }
  {
    AtomicOutput out(p.string());
    out.stream() << "new";
    EXPECT_EQ(slurp(p), "old");
    out.commit();
  }
  EXPECT_EQ(slurp(p), "new");
  // a non-finite trifocal is refused before anything is written
  Trifocal t;
  for (auto& Ti : t.T) Ti.setZero();
  auto pt = scratch("zero.trifocal");
  EXPECT_THROW(save_trifocal(pt.string(), t), NumericalError);
  EXPECT_FALSE(fs::exists(pt));
}

namespace {
// Runs f with the process's standard output sent to a file; returns what was written there.
template <class F>
std::string captured_stdout(F&& f) {
  const fs::path p = scratch("stdout.txt");
  std::cout.flush();
  std::fflush(stdout);
  const int saved = ::dup(1), fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ::dup2(fd, 1);
  ::close(fd);
  try {
    f();
  } catch (...) {
    std::cout.flush();
    ::dup2(saved, 1);
    ::close(saved);
    throw;
  }
  std::cout.flush();
  ::dup2(saved, 1);
  ::close(saved);
  return slurp(p);
}
}  // namespace

// Standard output is held until the commit (in a transaction, until the run commits; nothing when it
// aborts), then written whole and in order: here 5.3 MB, across the 2 MiB chunks that hold it, by
// characters, short strings, and a write of 3 MB that spans chunks.
TEST(Formats, AtomicOutputHoldsStandardOutputUntilTheCommit) {
  std::string expected;
  std::string before_commit = "unset";
  const std::string out = captured_stdout([&] {
    AtomicOutput o("-");
    for (int i = 0; i < 150000; ++i) {
      const std::string line = "record " + std::to_string(i) + " " + std::to_string(i * 7919 % 100003) + "\n";
      o.stream() << line;
      expected += line;
      o.stream().put(static_cast<char>('a' + i % 26));
      expected += static_cast<char>('a' + i % 26);
    }
    std::string big(3u << 20, ' ');
    for (size_t k = 0; k < big.size(); ++k) big[k] = static_cast<char>('0' + k % 10);
    o.stream().write(big.data(), static_cast<std::streamsize>(big.size()));
    expected += big;
    o.stream() << "end\n";
    expected += "end\n";
    std::cout.flush();
    before_commit = slurp(scratch("stdout.txt"));
    o.commit();
  });
  EXPECT_EQ(before_commit, "");
  ASSERT_GT(expected.size(), size_t(5) << 20);
  ASSERT_EQ(out.size(), expected.size());
  EXPECT_TRUE(out == expected);

  // in a transaction: written when the run commits, not at all when it aborts
  std::string pending = "unset";
  const std::string committed = captured_stdout([&] {
    begin_outputs();
    {
      AtomicOutput o("-");
      o.stream() << "first\n";
      o.commit();
    }
    std::cout.flush();
    pending = slurp(scratch("stdout.txt"));
    commit_outputs();
  });
  EXPECT_EQ(pending, "");
  EXPECT_EQ(committed, "first\n");
  const std::string aborted = captured_stdout([&] {
    begin_outputs();
    AtomicOutput o("-");
    o.stream() << "never\n";
    o.commit();
    abort_outputs();
  });
  EXPECT_EQ(aborted, "");
  const std::string empty = captured_stdout([&] {
    AtomicOutput o("-");
    o.commit();
  });
  EXPECT_EQ(empty, "");
  // a device is written in place, at the commit
  AtomicOutput dev("/dev/null");
  dev.stream() << expected;
  EXPECT_NO_THROW(dev.commit());
}

TEST(Formats, MissingFileIsAnInputError) {
  try {
    read_points("/nonexistent/dir/x.points");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/dir/x.points: no such file");
  }
}
