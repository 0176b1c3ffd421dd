// tp-chain's union-find: triplets from pairwise files, same-position duplicates, conflicts, positions
// referred to the reference keypoint, determinism.
#include "tpkit/match/tracks_chain.hpp"

#include <gtest/gtest.h>

#include "tpkit/core/error.hpp"

using namespace tpkit;

namespace {
// records: id1 x1 y1 id2 x2 y2 kx2 ky2
Matches make(const std::string& a, const std::string& b, const std::vector<std::array<double, 8>>& recs) {
  Matches m;
  m.image1 = {a, 100, 100};
  m.image2 = {b, 100, 100};
  m.xy.resize(static_cast<Eigen::Index>(recs.size()), 4);
  m.extra.names = {"kx2", "ky2"};
  m.extra.values.resize(static_cast<Eigen::Index>(recs.size()), 2);
  for (size_t i = 0; i < recs.size(); ++i) {
    const auto& r = recs[i];
    m.id1.push_back(static_cast<long long>(r[0]));
    m.id2.push_back(static_cast<long long>(r[3]));
    m.xy.row(static_cast<Eigen::Index>(i)) << r[1], r[2], r[4], r[5];
    m.extra.values.row(static_cast<Eigen::Index>(i)) << r[6], r[7];
  }
  return m;
}
}  // namespace

TEST(TracksChain, TripletsReferToTheReferenceKeypoint) {
  // keypoint 5 of A at (10, 20); B's keypoint 7 at (11, 21) refined to (11.2, 21.1) against A:5;
  // C's keypoint 9 at (30, 40) refined to (30.3, 40.1) against A:5.
  auto ab = make("A", "B", {{{5, 10, 20, 7, 11.2, 21.1, 11, 21}}, {{6, 50, 50, 8, 52, 51, 52, 51}}});
  auto ac = make("A", "C", {{{5, 10, 20, 9, 30.3, 40.1, 30, 40}}});
  auto bc = make("B", "C", {{{7, 11, 21, 9, 30.05, 40.0, 30, 40}}});
  ChainOptions o;
  ChainStats st;
  Tracks t = chain_tracks({ab, ac, bc}, o, &st);
  ASSERT_EQ(t.size(), 1u);
  ASSERT_EQ(t.views(), 3);
  EXPECT_EQ(t.images[0].path, "A");
  EXPECT_EQ(t.images[2].path, "C");
  EXPECT_DOUBLE_EQ(t.xy(0, 0), 10);
  EXPECT_DOUBLE_EQ(t.xy(0, 1), 20);
  EXPECT_DOUBLE_EQ(t.xy(0, 2), 11.2);  // direct links with the reference are taken exactly
  EXPECT_DOUBLE_EQ(t.xy(0, 3), 21.1);
  EXPECT_DOUBLE_EQ(t.xy(0, 4), 30.3);
  EXPECT_DOUBLE_EQ(t.xy(0, 5), 40.1);
  EXPECT_EQ(st.by_length[3], 1);
  EXPECT_EQ(st.by_length[2], 1);
  EXPECT_EQ(t.extra.values(0, 0), 5);
}

TEST(TracksChain, IndirectViewMovesByTheRefinedOffset) {
  // C is only linked through B: C = x2(BC) + (pos(B) - kp(B)) = (30.05, 40) + (0.2, 0.1)
  auto ab = make("A", "B", {{{5, 10, 20, 7, 11.2, 21.1, 11, 21}}});
  auto bc = make("B", "C", {{{7, 11, 21, 9, 30.05, 40.0, 30, 40}}});
  Tracks t = chain_tracks({ab, bc}, ChainOptions{}, nullptr);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_NEAR(t.xy(0, 4), 30.25, 1e-12);
  EXPECT_NEAR(t.xy(0, 5), 40.1, 1e-12);
  // reversed file (C as image 1): B's refined position given C's keypoint moves C the other way
  auto cb = make("C", "B", {{{9, 30, 40, 7, 11.3, 21.0, 11, 21}}});
  Tracks r = chain_tracks({ab, cb}, ChainOptions{{"A", "B", "C"}, 3, 0.01}, nullptr);
  ASSERT_EQ(r.size(), 1u);
  // pos(C) = kp(C) - (x2 - pos(B)) = (30, 40) - ((11.3, 21.0) - (11.2, 21.1))
  EXPECT_NEAR(r.xy(0, 4), 29.9, 1e-12);
  EXPECT_NEAR(r.xy(0, 5), 40.1, 1e-12);
}

TEST(TracksChain, SamePositionKeypointsMergeConflictsDrop) {
  // A:1 and A:2 are one position (two SIFT orientations): their links form one triplet
  auto ab = make("A", "B", {{{1, 10, 10, 3, 12, 12, 12, 12}}, {{20, 70, 70, 21, 71, 71, 71, 71}}});
  auto ac = make("A", "C", {{{2, 10, 10, 4, 14, 14, 14, 14}}, {{20, 70, 70, 22, 72, 72, 72, 72}},
                            {{25, 80, 80, 22, 72.1, 72, 72, 72}}});  // C:22 also linked to A:25 elsewhere: conflict
  ChainStats st;
  Tracks t = chain_tracks({ab, ac}, ChainOptions{}, &st);
  EXPECT_EQ(st.merged_duplicates, 1);
  EXPECT_EQ(st.dropped_reference_conflicts, 1);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_DOUBLE_EQ(t.xy(0, 2), 12);
  EXPECT_DOUBLE_EQ(t.xy(0, 4), 14);
}

TEST(TracksChain, ImagesOrderAndErrors) {
  auto ab = make("A", "B", {{{5, 10, 20, 7, 11.2, 21.1, 11, 21}}});
  auto ac = make("A", "C", {{{5, 10, 20, 9, 30.3, 40.1, 30, 40}}});
  ChainOptions o;
  o.images = {"C", "A", "B"};  // C is the reference: its keypoint (30, 40)
  Tracks t = chain_tracks({ab, ac}, o, nullptr);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_DOUBLE_EQ(t.xy(0, 0), 30);
  EXPECT_DOUBLE_EQ(t.xy(0, 1), 40);
  // A = kp(A) - (x2 - kp(C)) = (10, 20) - (0.3, 0.1)
  EXPECT_NEAR(t.xy(0, 2), 9.7, 1e-12);
  o.images = {"A", "D"};
  EXPECT_THROW(chain_tracks({ab, ac}, o, nullptr), InputError);
  o.images = {"A", "B"};
  o.min_views = 3;
  EXPECT_THROW(chain_tracks({ab, ac}, o, nullptr), UsageError);
  o.min_views = 2;
  Tracks two = chain_tracks({ab, ac}, o, nullptr);
  EXPECT_EQ(two.views(), 2);
  EXPECT_EQ(two.size(), 1u);
}

TEST(TracksChain, DeterministicWhateverTheFileOrder) {
  std::vector<std::array<double, 8>> r12, r13;
  for (int i = 0; i < 200; ++i) {
    r12.push_back({{double(i), double(i), 2.0 * i, double(1000 + i), i + 0.5, 2.0 * i + 0.25, i + 0.5, 2.0 * i + 0.25}});
    r13.push_back({{double(199 - i), double(199 - i), 2.0 * (199 - i), double(2000 + i), 5.0 + i, 7.0, 5.0 + i, 7.0}});
  }
  auto ab = make("A", "B", r12), ac = make("A", "C", r13);
  ChainOptions o;
  o.images = {"A", "B", "C"};
  Tracks t1 = chain_tracks({ab, ac}, o, nullptr), t2 = chain_tracks({ac, ab}, o, nullptr);
  ASSERT_EQ(t1.size(), 200u);
  EXPECT_TRUE(t1.xy == t2.xy);
  EXPECT_DOUBLE_EQ(t1.xy(3, 0), 3.0);  // sorted by reference keypoint id
}
