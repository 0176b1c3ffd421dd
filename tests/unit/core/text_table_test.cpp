// Tests of the generic text layer: headers, comments, column lookup, headerless input, errors with
// file:line, number formatting.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/version.hpp"

using namespace tpkit;

namespace {
TextTable parse(const std::string& text, const ReadOptions& opt) {
  std::istringstream in(text);
  return read_table(in, "test.txt", opt);
}

std::string error_of(const std::string& text, const ReadOptions& opt) {
  try {
    parse(text, opt);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(TextTable, HeaderImagesMetaColumnsAndComments) {
  auto t = parse(
      "# tpkit matches 1\n"
      "# image1: a b.tif 1024 768\n"
      "# image2: c.tif 10 20\n"
      "# detector: sift nfeatures=0\n"
      "# a free comment\n"
      "# columns: id1 x1 y1 id2 x2 y2 sigma\n"
      "\n"
      "1 2.5 3.5 7 8 9 0.01\n"
      "# comment between records\n"
      "  2 -1e-3 +4 8 1 2 0.02  \n",
      matches_read_options());
  EXPECT_EQ(t.kind, "matches");
  EXPECT_EQ(t.version, 1);
  ASSERT_EQ(t.images.size(), 2u);
  EXPECT_EQ(t.images[0].path, "a b.tif");
  EXPECT_EQ(t.images[0].width, 1024);
  EXPECT_EQ(t.images[0].height, 768);
  EXPECT_EQ(meta_get(t.meta, "detector"), "sift nfeatures=0");
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.row_line[0], 8);
  EXPECT_EQ(t.row_line[1], 10);
  EXPECT_EQ(t.find("sigma"), 6);
  EXPECT_DOUBLE_EQ(t.rows[1][1], -1e-3);
  EXPECT_DOUBLE_EQ(t.rows[1][2], 4);
}

TEST(TextTable, ErrorsNameFileAndLine) {
  auto o = matches_read_options();
  EXPECT_EQ(error_of("# tpkit matches 1\n# columns: id1 x1 y1 id2 x2 y2\n1 2 3 4 5 abc\n", o),
            "test.txt:3: field 'y2' is not a number: 'abc'");
  EXPECT_EQ(error_of("# tpkit matches 1\n# columns: id1 x1 y1 id2 x2 y2\n1 2 3 4 5 nan\n", o),
            "test.txt:3: field 'y2' is not finite: 'nan'");
  EXPECT_EQ(error_of("# tpkit matches 1\n# columns: id1 x1 y1 id2 x2 y2\n1 2 3 4 inf 1\n", o),
            "test.txt:3: field 'x2' is not finite: 'inf'");
  EXPECT_EQ(error_of("# tpkit matches 1\n# columns: id1 x1 y1 id2 x2 y2\n\n1 2 3 4 5\n", o),
            "test.txt:4: missing column 'y2' (5 fields, 6 columns)");
  EXPECT_EQ(error_of("# tpkit tracks 1\n# columns: track x1 y1 x2 y2\n", o),
            "test.txt:1: wrong header kind: expected 'matches', found 'tracks'");
  EXPECT_EQ(error_of("# tpkit matches 2\n", o), "test.txt:1: version 2 of 'matches' is newer than this reader (1)");
  EXPECT_EQ(error_of("# tpkit matches 1\n1 2 3 4 5 6\n", o), "test.txt:2: record before any '# columns:' line");
  EXPECT_EQ(error_of("1 2 3\n", o),
            "test.txt:1: headerless input with 3 fields does not fit the default columns of 'matches'");
  EXPECT_NE(error_of("# tpkit matches 1\n# columns: x1 x1\n", o).find("named twice"), std::string::npos);
  EXPECT_NE(error_of(std::string("1 2 3 4 5 6\n1 2\0 3 4 5 6\n", 25), o).find("test.txt:2: binary data"), std::string::npos);
}

TEST(TextTable, HeaderlessInputGetsDefaultColumns) {
  auto m = matches_from_table(parse("1 10 20 2 11 21\n3 30 40 4 31 41\n", matches_read_options()));
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m.id1[1], 3);
  EXPECT_EQ(m.id2[1], 4);
  EXPECT_DOUBLE_EQ(m.xy(1, 3), 41);
  auto m4 = matches_from_table(parse("10 20 11 21\n30 40 31 41\n", matches_read_options()));
  EXPECT_EQ(m4.id1[1], 1);  // record index
  auto t6 = tracks_from_table(parse("1 2 3 4 5 6\n", tracks_read_options()));
  EXPECT_EQ(t6.views(), 3);
  EXPECT_EQ(t6.id[0], 0);
  auto t7 = tracks_from_table(parse("9 1 2 3 4 5 6\n", tracks_read_options()));
  EXPECT_EQ(t7.views(), 3);
  EXPECT_EQ(t7.id[0], 9);
  EXPECT_DOUBLE_EQ(t7.point(0, 2).y(), 6);
  auto p = points_from_table(parse("1 2\n3 4\n", points_read_options()));
  EXPECT_EQ(p.size(), 2u);
}

TEST(TextTable, ColumnsFoundByNameInAnyOrderExtrasKept) {
  auto m = matches_from_table(parse(
      "# tpkit matches 1\n# columns: score y2 x2 id2 y1 x1 id1\n0.5 4 3 20 2 1 10\n", matches_read_options()));
  EXPECT_EQ(m.id1[0], 10);
  EXPECT_EQ(m.id2[0], 20);
  EXPECT_DOUBLE_EQ(m.xy(0, 0), 1);
  EXPECT_DOUBLE_EQ(m.xy(0, 3), 4);
  ASSERT_EQ(m.extra.names.size(), 1u);
  EXPECT_EQ(m.extra.names[0], "score");
  EXPECT_DOUBLE_EQ(m.extra.values(0, 0), 0.5);
  std::ostringstream os;
  write_matches(os, m);
  EXPECT_NE(os.str().find("# columns: id1 x1 y1 id2 x2 y2 score\n10 1 2 20 3 4 0.5\n"), std::string::npos);
}

TEST(TextTable, NumbersRoundTripExactly) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-30000, 30000);
  for (int i = 0; i < 2000; ++i) {
    double v = i % 3 ? u(rng) : u(rng) * 1e-9;
    std::string s = format_number(v);
    std::istringstream in("# tpkit points 1\n# columns: x y\n" + s + " 0\n");
    auto t = read_table(in, "-", points_read_options());
    ASSERT_EQ(t.rows[0][0], v) << s;
  }
  EXPECT_EQ(format_number(512.0), "512");
  EXPECT_EQ(format_number(-0.0), "0");
  EXPECT_EQ(format_number(0.1), "0.1");
  EXPECT_EQ(format_id(123456789012.0), "123456789012");
}

TEST(TextTable, IdsMustBeIntegers) {
  try {
    matches_from_table(parse("# tpkit matches 1\n# columns: id1 x1 y1 id2 x2 y2\n1.5 1 2 3 4 5\n", matches_read_options()));
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "test.txt:3: field 'id1' is not an integer id");
  }
}

TEST(TextTable, MissingColumnNamed) {
  try {
    tracks_from_table(parse("# tpkit tracks 1\n# columns: track x1 y1 x2 y2 x3\n1 1 2 3 4 5\n", tracks_read_options()));
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "test.txt: missing column 'y3'");
  }
}

TEST(TextTable, WrittenByNamesTheWriterAndIsNotCarriedAlong) {
  // a file read and written again names its new writer once, not its first writer as metadata
  std::ostringstream os;
  write_header(os, "matches", 1, {}, {{"method", "x"}}, {"id1", "x1", "y1", "id2", "x2", "y2"});
  const std::string first = os.str();
  EXPECT_NE(first.find("# tpkit matches 1\n# written-by: "), std::string::npos) << first;
  EXPECT_NE(first.find(std::string("# written-by: ") + written_by() + "\n"), std::string::npos) << first;
  EXPECT_NE(written_by().find(version()), std::string::npos);
  auto t = parse(first + "1 2 3 4 5 6\n", matches_read_options());
  EXPECT_EQ(t.written_by, written_by());
  ASSERT_EQ(t.meta.size(), 1u);
  EXPECT_EQ(t.meta[0].first, "method");
  std::ostringstream again;
  write_header(again, t.kind, t.version, t.images, t.meta, t.columns);
  EXPECT_EQ(again.str(), first);
}

TEST(TextTable, HeaderMustBeTheFirstLine) {
  ReadOptions o = matches_read_options();
  // a comment above the header would make it a free comment, and kind and version go unchecked
  EXPECT_NE(error_of("# note\n# tpkit tracks 99\n# columns: id1 x1 y1 id2 x2 y2\n1 2 3 4 5 6\n", o)
                .find("test.txt:2: the '# tpkit KIND VERSION' header must be the first line"),
            std::string::npos);
  EXPECT_NE(error_of("# tpkit matches 1\n# columns: id1 x1 y1 id2 x2 y2\n1 2 3 4 5 6\n# tpkit matches 1\n", o)
                .find("test.txt:4: a second"),
            std::string::npos);
  // a byte order mark before the header is not a bad character
  auto t = parse("\xEF\xBB\xBF# tpkit matches 1\n# columns: id1 x1 y1 id2 x2 y2\n1 2 3 4 5 6\n", o);
  EXPECT_EQ(t.kind, "matches");
  EXPECT_EQ(t.rows.size(), 1u);
}

TEST(TextTable, BinaryAndOverlongLinesFailAsTheyAreRead) {
  // a stream of NUL bytes with no newline, or one endless line, is refused without reading it whole
  struct Endless : std::streambuf {
    char fill;
    long served = 0;
    char buf[4096];
    explicit Endless(char c) : fill(c) {}
    int_type underflow() override {
      std::fill(buf, buf + sizeof buf, fill);
      served += sizeof buf;
      setg(buf, buf, buf + sizeof buf);
      return traits_type::to_int_type(fill);
    }
  };
  for (char c : {'\0', '7'}) {
    Endless sb(c);
    std::istream in(&sb);
    std::string msg;
    try {
      read_table(in, "dev", matches_read_options());
    } catch (const InputError& e) {
      msg = e.what();
    }
    EXPECT_NE(msg.find(c == '\0' ? "dev:1: binary data" : "dev:1: line longer than"), std::string::npos) << msg;
    EXPECT_LT(sb.served, 4L << 20) << "read far past the first bad byte";
  }
}
