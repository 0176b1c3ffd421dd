// tp-chain's union-find: triplets from pairwise files, same-position duplicates, conflicts, positions
// referred to the reference keypoint, determinism.
#include "tpkit/match/tracks_chain.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

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

// Issue 24: a block of 8 images, each ground point seen by a random subset of them (2 to 8), matched in
// every pair of its views (an image's keypoint ids are its own): every point comes back as one track
// with exactly its views, at its positions, the incomplete ones with nan, whatever the file order.
TEST(TracksChain, BlockTracksOfAnyLength) {
  const int N = 8, P = 400;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0, 1000);
  std::vector<std::vector<int>> sees(P);
  std::vector<std::vector<Eigen::Vector2d>> at(P, std::vector<Eigen::Vector2d>(N));
  std::map<std::pair<int, int>, std::vector<std::array<double, 8>>> recs;
  auto name = [](int i) { return "img" + std::to_string(i); };
  std::map<int, long> by_length;
  for (int p = 0; p < P; ++p) {
    for (int i = 0; i < N; ++i) {
      if (rng() % 3 == 0) sees[p].push_back(i);
      at[p][i] = {U(rng), U(rng)};
    }
    if (sees[p].size() < 2) sees[p] = {static_cast<int>(rng() % 4), 4 + static_cast<int>(rng() % 4)};
    by_length[static_cast<int>(sees[p].size())]++;
    for (size_t a = 0; a < sees[p].size(); ++a)
      for (size_t b = a + 1; b < sees[p].size(); ++b) {
        const int i = sees[p][a], j = sees[p][b];
        const Eigen::Vector2d u = at[p][i], v = at[p][j];
        recs[{i, j}].push_back({{double(1000 * i + p), u.x(), u.y(), double(1000 * j + p), v.x(), v.y(), v.x(), v.y()}});
      }
  }
  std::vector<Matches> files;
  for (const auto& kv : recs) files.push_back(make(name(kv.first.first), name(kv.first.second), kv.second));
  for (auto& m : files) m.image1.width = m.image1.height = m.image2.width = m.image2.height = 1000;
  ChainOptions o;
  for (int i = 0; i < N; ++i) o.images.push_back(name(i));
  o.min_views = 2;
  ChainStats st;
  const Tracks t = chain_tracks(files, o, &st);
  ASSERT_EQ(t.size(), static_cast<size_t>(P));
  EXPECT_EQ(st.by_length, by_length);
  EXPECT_EQ(st.written_by_length, by_length);
  const int ckp = t.extra.find("kp"), cref = t.extra.find("ref");
  ASSERT_GE(ckp, 0);
  ASSERT_GE(cref, 0);
  std::set<int> found;
  for (size_t r = 0; r < t.size(); ++r) {
    const int ref = static_cast<int>(t.extra.values(static_cast<Eigen::Index>(r), cref)) - 1;
    const int p = static_cast<int>(t.extra.values(static_cast<Eigen::Index>(r), ckp)) - 1000 * ref;
    ASSERT_TRUE(p >= 0 && p < P);
    found.insert(p);
    EXPECT_EQ(ref, sees[p][0]);
    EXPECT_EQ(t.seen_views(r), static_cast<int>(sees[p].size()));
    for (int i : sees[p]) {
      ASSERT_TRUE(t.seen(r, i));
      EXPECT_EQ(t.point(r, i), at[p][i]);
    }
  }
  EXPECT_EQ(found.size(), static_cast<size_t>(P));
  // the same tracks from the files in reverse order; and --min-views 5 keeps the long ones only
  std::vector<Matches> rev(files.rbegin(), files.rend());
  const Tracks t2 = chain_tracks(rev, o, nullptr);
  EXPECT_TRUE(t2.xy.cwiseEqual(t.xy).count() + t2.xy.array().isNaN().count() == t.xy.size());
  o.min_views = 5;
  const Tracks t5 = chain_tracks(files, o, &st);
  long five = 0;
  for (const auto& kv : by_length) five += kv.first >= 5 ? kv.second : 0;
  EXPECT_EQ(static_cast<long>(t5.size()), five);
}

TEST(TracksChain, LoopClosureDropsTheViewAWrongLinkContradicts) {
  // A-B and A-C place C at (30.3, 40.1); B-C, moved by B's offset (0.2, 0.1), puts it at (31.75, 40.1):
  // 1.45 px apart, so one of the three links is wrong and C, reached after B, loses its place.
  auto ab = make("A", "B", {{{5, 10, 20, 7, 11.2, 21.1, 11, 21}}});
  auto ac = make("A", "C", {{{5, 10, 20, 9, 30.3, 40.1, 30, 40}}});
  auto bc = make("B", "C", {{{7, 11, 21, 9, 31.55, 40.0, 30, 40}}});
  ChainOptions o;
  ChainStats st;
  EXPECT_EQ(chain_tracks({ab, ac, bc}, o, &st).size(), 0u);
  EXPECT_EQ(st.views_dropped_closure, 1);
  o.min_views = 2;
  Tracks t = chain_tracks({ab, ac, bc}, o, nullptr);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_DOUBLE_EQ(t.xy(0, 2), 11.2);
  EXPECT_TRUE(std::isnan(t.xy(0, 4)));
  o.closure = 1.5;  // within the tolerance: kept
  EXPECT_DOUBLE_EQ(chain_tracks({ab, ac, bc}, o, nullptr).xy(0, 4), 30.3);
  o.closure = 0;  // no check
  EXPECT_DOUBLE_EQ(chain_tracks({ab, ac, bc}, o, nullptr).xy(0, 4), 30.3);
}

TEST(TracksChain, LoopClosureToleranceGrowsWithTheCycleSigmas) {
  // the same 1.45 px disagreement on records of sigma 0.5 px (unrefined matches): the cycle's sigma is
  // sqrt(3) x 0.5 = 0.87 px, so 5 sigma = 4.3 px and C stays
  auto with_sigma = [](Matches m) {
    m.extra.names.push_back("sigma");
    m.extra.values.conservativeResize(Eigen::NoChange, 3);
    m.extra.values.col(2).setConstant(0.5);
    return m;
  };
  auto ab = with_sigma(make("A", "B", {{{5, 10, 20, 7, 11.2, 21.1, 11, 21}}}));
  auto ac = with_sigma(make("A", "C", {{{5, 10, 20, 9, 30.3, 40.1, 30, 40}}}));
  auto bc = with_sigma(make("B", "C", {{{7, 11, 21, 9, 31.55, 40.0, 30, 40}}}));
  ChainStats st;
  Tracks t = chain_tracks({ab, ac, bc}, ChainOptions{}, &st);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(st.views_dropped_closure, 0);
  EXPECT_DOUBLE_EQ(t.xy(0, 4), 30.3);
}

namespace {
// A block of N images and P ground points with truth, every pair of a point's views matched (as
// tp-plan's pairs are). Image i sees point p at truth[p][i]; its keypoint there is off by up to
// 0.4 px; a record i -> j (i < j) keeps image i's keypoint and gives image j's position of the same
// ground point, i.e. truth + the keypoint's offset in image i (the refined offset; noise 0.03 px).
// A wrong view w of a track: each of its records is off by 3.5 px in a direction of its own (its
// partners disagree with it, each differently: repeated patterns, a refinement gone astray; a view
// whose records all agree on a wrong point is the RPC check's to find, tracks_epipolar_check).
struct Block {
  int N = 8;
  std::vector<std::vector<int>> sees;
  std::vector<std::vector<Eigen::Vector2d>> truth, kp;
  std::vector<int> wrong;                      // per point: the wrong view, -1 none
  std::vector<std::pair<int, int>> bad_link;   // per point: one bad record between two good views, {-1,-1} none
  std::vector<Matches> files;
};

Block make_block(int P, unsigned seed, double wrong_share, double bad_link_share) {
  Block B;
  B.sees.resize(static_cast<size_t>(P));
  B.truth.assign(static_cast<size_t>(P), std::vector<Eigen::Vector2d>(static_cast<size_t>(B.N)));
  B.kp = B.truth;
  B.wrong.assign(static_cast<size_t>(P), -1);
  B.bad_link.assign(static_cast<size_t>(P), {-1, -1});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1000), K(-0.4, 0.4), Uni(0, 1);
  std::normal_distribution<double> noise(0, 0.03);
  std::map<std::pair<int, int>, std::vector<std::array<double, 8>>> recs;
  for (int p = 0; p < P; ++p) {
    auto& s = B.sees[static_cast<size_t>(p)];
    while (s.size() < 4) {
      s.clear();
      for (int i = 0; i < B.N; ++i)
        if (Uni(rng) < 0.6) s.push_back(i);
    }
    for (int i = 0; i < B.N; ++i) {
      B.truth[static_cast<size_t>(p)][static_cast<size_t>(i)] = {U(rng), U(rng)};
      B.kp[static_cast<size_t>(p)][static_cast<size_t>(i)] = B.truth[static_cast<size_t>(p)][static_cast<size_t>(i)] + Eigen::Vector2d(K(rng), K(rng));
    }
    const double u = Uni(rng);
    if (u < wrong_share) {
      B.wrong[static_cast<size_t>(p)] = s[rng() % s.size()];
    } else if (u < wrong_share + bad_link_share && s.size() >= 5) {
      const size_t a = rng() % s.size(), b = (a + 1 + rng() % (s.size() - 1)) % s.size();
      B.bad_link[static_cast<size_t>(p)] = {std::min(s[a], s[b]), std::max(s[a], s[b])};
    }
    const double phase = 2 * M_PI * Uni(rng);
    for (size_t a = 0; a < s.size(); ++a)
      for (size_t b = a + 1; b < s.size(); ++b) {
        const int i = s[a], j = s[b];
        const auto& T = B.truth[static_cast<size_t>(p)];
        const auto& KP = B.kp[static_cast<size_t>(p)];
        Eigen::Vector2d x2 = T[static_cast<size_t>(j)] + (KP[static_cast<size_t>(i)] - T[static_cast<size_t>(i)]) +
                             Eigen::Vector2d(noise(rng), noise(rng));
        const int w = B.wrong[static_cast<size_t>(p)];
        if (w == i || w == j) {
          // the move each record gives w: +e for a record into w, -e for one out of it; their
          // directions 2 pi / N apart and shifted by half a step between the two kinds, so that no two
          // of them agree (they differ by 1.3 px or more)
          const int partner = w == i ? j : i;
          const double ang = phase + 2 * M_PI * partner / B.N + (w == i ? M_PI / B.N : 0.0);
          x2 += 3.5 * Eigen::Vector2d(std::cos(ang), std::sin(ang));
        }
        if (B.bad_link[static_cast<size_t>(p)] == std::make_pair(i, j)) x2 += Eigen::Vector2d(2.0, -1.5);
        recs[{i, j}].push_back({{double(1000 * i + p), KP[static_cast<size_t>(i)].x(), KP[static_cast<size_t>(i)].y(),
                                 double(1000 * j + p), x2.x(), x2.y(), KP[static_cast<size_t>(j)].x(), KP[static_cast<size_t>(j)].y()}});
      }
  }
  for (const auto& kv : recs) {
    Matches m = make("img" + std::to_string(kv.first.first), "img" + std::to_string(kv.first.second), kv.second);
    m.image1.width = m.image1.height = m.image2.width = m.image2.height = 1000;
    B.files.push_back(std::move(m));
  }
  return B;
}
}  // namespace

// Issue 51: the loop closure over every cycle of a block's tracks. A track with one wrong view loses
// that view (the one inconsistent with the most others), not the whole track and not a good view; a
// lone bad record between two good views is left out and both keep their place; the positions of the
// views kept are the truth (referred to the reference keypoint), also where the reference view itself
// was the wrong one (the track then refers to its next image's keypoint).
TEST(TracksChain, LoopClosureDropsTheWrongViewOfABlockTrack) {
  const int P = 600;
  const Block B = make_block(P, 11, 0.25, 0.15);
  ChainOptions o;
  for (int i = 0; i < B.N; ++i) o.images.push_back("img" + std::to_string(i));
  o.min_views = 2;
  ChainStats st;
  const Tracks t = chain_tracks(B.files, o, &st);
  ASSERT_EQ(t.size(), static_cast<size_t>(P));  // no track lost
  const int ckp = t.extra.find("kp"), cref = t.extra.find("ref");
  long injected = 0, wrong_dropped = 0, good_lost = 0, good_kept = 0, bad_links = 0, far = 0, ref_wrong = 0;
  double worst = 0;
  for (size_t r = 0; r < t.size(); ++r) {
    const int ref = static_cast<int>(t.extra.values(static_cast<Eigen::Index>(r), cref)) - 1;
    const int p = static_cast<int>(t.extra.values(static_cast<Eigen::Index>(r), ckp)) - 1000 * ref;
    ASSERT_TRUE(p >= 0 && p < P);
    const int w = B.wrong[static_cast<size_t>(p)];
    injected += w >= 0;
    ref_wrong += w >= 0 && w == B.sees[static_cast<size_t>(p)][0];
    bad_links += B.bad_link[static_cast<size_t>(p)].first >= 0;
    const Eigen::Vector2d delta = B.kp[static_cast<size_t>(p)][static_cast<size_t>(ref)] - B.truth[static_cast<size_t>(p)][static_cast<size_t>(ref)];
    for (int i : B.sees[static_cast<size_t>(p)]) {
      if (i == w) {
        wrong_dropped += !t.seen(r, i);
        continue;
      }
      if (!t.seen(r, i)) {
        ++good_lost;
        continue;
      }
      ++good_kept;
      const double e = (t.point(r, i) - (B.truth[static_cast<size_t>(p)][static_cast<size_t>(i)] + delta)).norm();
      worst = std::max(worst, e);
      far += e > 0.3;
    }
  }
  ASSERT_GT(injected, 100);
  ASSERT_GT(ref_wrong, 10);
  ASSERT_GT(bad_links, 40);
  EXPECT_EQ(wrong_dropped, injected);                         // every wrong view goes
  EXPECT_LE(good_lost, 0.01 * static_cast<double>(good_kept));  // and hardly a good one
  EXPECT_EQ(far, 0) << "worst " << worst << " px";            // the views kept sit on the truth
  EXPECT_EQ(st.views_dropped_closure, wrong_dropped + good_lost);
  EXPECT_GE(st.links_dropped_closure, bad_links);
  // the former rule (the view reached later goes) kept the wrong view of some tracks and dropped good
  // ones: here every kept view is on the truth within 0.3 px
}
