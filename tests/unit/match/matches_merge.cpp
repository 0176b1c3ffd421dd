// tp-merge's rules: duplicates once, conflicts resolved towards the record deepest inside its file's
// region, files of another pair or detector refused, output sorted by (id1, id2).
#include "tpkit/match/matches_merge.hpp"

#include <gtest/gtest.h>

#include "tpkit/core/error.hpp"

using namespace tpkit;

namespace {
// records: id1 x1 y1 id2 x2 y2
Matches file(const std::string& name, const std::string& region, const std::vector<std::array<double, 6>>& recs) {
  Matches m;
  m.source = name;
  m.image1 = {"a.tif", 100, 100};
  m.image2 = {"b.tif", 100, 100};
  meta_set(m.meta, "detector1", "d");
  meta_set(m.meta, "detector2", "d");
  if (!region.empty()) meta_set(m.meta, "region", region);
  m.xy.resize(static_cast<Eigen::Index>(recs.size()), 4);
  m.extra.values.resize(static_cast<Eigen::Index>(recs.size()), 0);
  for (size_t k = 0; k < recs.size(); ++k) {
    const auto& r = recs[k];
    m.id1.push_back(static_cast<long long>(r[0]));
    m.id2.push_back(static_cast<long long>(r[3]));
    m.xy.row(static_cast<Eigen::Index>(k)) << r[1], r[2], r[4], r[5];
  }
  return m;
}
}  // namespace

TEST(MatchesMerge, DuplicatesAndConflicts) {
  // region A: x in [-0.5, 49.5); region B: [40 - 0.5, 100 - 0.5) (overlap 40..49)
  const Matches a = file("A", "0 0 50 100 (x0 y0 width height)", {{{7, 10, 10, 70, 11, 11}}, {{3, 45, 50, 30, 46, 51}}, {{5, 48, 20, 50, 49, 21}}});
  const Matches b = file("B", "40 0 60 100", {{{3, 45, 50, 30, 46, 51}}, {{5, 48, 20, 51, 49.5, 21}}, {{9, 90, 90, 90, 91, 91}}});
  MergeStats st;
  const Matches m = merge_matches({a, b}, &st);
  EXPECT_EQ(st.records, 6);
  EXPECT_EQ(st.duplicates, 1);  // (3, 30)
  EXPECT_EQ(st.conflicts, 1);   // id1 5: 50 in A (x 48: 1.5 px inside A), 51 in B (8.5 px inside B)
  ASSERT_EQ(m.size(), 4u);
  EXPECT_EQ(m.id1, (std::vector<long long>{3, 5, 7, 9}));
  EXPECT_EQ(m.id2, (std::vector<long long>{30, 51, 70, 90}));
  EXPECT_DOUBLE_EQ(m.xy(1, 2), 49.5);
  EXPECT_EQ(meta_get(m.meta, "region"), "");
  EXPECT_NE(meta_get(m.meta, "merged").find("2 files, 6 records: 1 duplicates, 1 conflicts dropped, 4 written"), std::string::npos);
}

TEST(MatchesMerge, SecondImageConflictAndWholeFileWins) {
  // id2 40 matched by id1 1 in a region file and by id1 2 in a whole-image file: the whole file wins
  const Matches a = file("A", "0 0 10 10", {{{1, 5, 5, 40, 6, 6}}});
  const Matches w = file("W", "", {{{2, 50, 50, 40, 51, 51}}});
  const Matches m = merge_matches({a, w});
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m.id1[0], 2);
}

TEST(MatchesMerge, RefusesOtherPairOrDetector) {
  const Matches a = file("A", "", {});
  Matches b = file("B", "", {});
  b.image2.path = "c.tif";
  EXPECT_THROW(merge_matches({a, b}), InputError);
  Matches c = file("C", "", {});
  meta_set(c.meta, "detector1", "other");
  EXPECT_THROW(merge_matches({a, c}), InputError);
  EXPECT_THROW(merge_matches({}), UsageError);
}
