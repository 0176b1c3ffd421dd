// Guided descriptor matching on a synthetic affine pair with known correspondences: the epipolar band
// and parallax ranges find the true pairs and only them, the ratio test rejects repeated texture along
// the band, the result does not depend on the thread count; and the keypoint cache round trip.
#include "tpkit/match/guided_matching.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <array>
#include <climits>
#include <random>

#include "tpkit/match/keypoint_cache.hpp"

using namespace tpkit;

namespace {

// n true points: image 2 = affine map of image 1 + parallax along the direction (cos 10 deg, sin 10 deg)
// (the epipolar direction), in [-30, 40] px; descriptors = a random base vector + small noise.
// `distractors` extra keypoints in each image with unrelated descriptors.
struct Pair {
  Keypoints K1, K2;
  std::vector<int> truth;  // truth[i] = row of K2 matching row i of K1 (first n rows), else -1
};

Pair make_pair(int n, int distractors, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> ux(0, 1000), upar(-30, 40);
  std::normal_distribution<float> noise(0, 4);
  std::uniform_int_distribution<int> byte(0, 255);
  Pair p;
  const int m = n + distractors;
  p.K1.desc.create(m, 128, CV_8U);
  p.K2.desc.create(m, 128, CV_8U);
  const float c = std::cos(0.1745f), s = std::sin(0.1745f);
  for (int i = 0; i < m; ++i) {
    const float x = ux(rng), y = ux(rng);
    p.K1.kp.emplace_back(x, y, 4.f, 0.f, 0.01f + 0.001f * (i % 7));
    p.K1.id.push_back(i);
    for (int k = 0; k < 128; ++k) p.K1.desc.at<uint8_t>(i, k) = static_cast<uint8_t>(byte(rng));
  }
  for (int i = 0; i < m; ++i) {
    if (i < n) {
      const float x = p.K1.kp[i].pt.x, y = p.K1.kp[i].pt.y, par = upar(rng);
      p.K2.kp.emplace_back(0.98f * x + 0.05f * y + 12 + par * c, -0.04f * x + 1.01f * y - 7 + par * s, 4.f, 0.f, 0.01f);
      for (int k = 0; k < 128; ++k)
        p.K2.desc.at<uint8_t>(i, k) =
            static_cast<uint8_t>(std::clamp(static_cast<float>(p.K1.desc.at<uint8_t>(i, k)) + noise(rng), 0.f, 255.f));
    } else {
      p.K2.kp.emplace_back(ux(rng), ux(rng), 4.f, 0.f, 0.01f);
      for (int k = 0; k < 128; ++k) p.K2.desc.at<uint8_t>(i, k) = static_cast<uint8_t>(byte(rng));
    }
    p.K2.id.push_back(i);
    p.truth.push_back(i < n ? i : -1);
  }
  return p;
}

GuidedMatchResult run(const Pair& p, int threads, GuidedMatchOptions g = {}) {
  AffineFundamentalRansac r;
  r.threshold = 1.0;
  return guided_match(p.K1, p.K2, 1000, 1000, DescriptorMatchOptions{}, g, r, 12, threads);
}

}  // namespace

TEST(GuidedMatch, FindsTheTruePairsOnly) {
  const Pair p = make_pair(3000, 3000, 1);
  const GuidedMatchResult g = run(p, 2);
  ASSERT_TRUE(g.ok);
  long right = 0, wrong = 0;
  for (const auto& m : g.matches) (p.truth[m.i1] == m.i2 ? right : wrong)++;
  EXPECT_GE(right, 2970);
  EXPECT_EQ(wrong, 0);
  EXPECT_NEAR(g.parallax_max - g.parallax_min, 70.0, 3.0);  // the parallax span of the scene
  EXPECT_LT(g.candidates_per_query, 200.0);                // far from the 6000 of a global search
}

TEST(GuidedMatch, SameResultForAnyThreadCount) {
  const Pair p = make_pair(2000, 1000, 2);
  const GuidedMatchResult a = run(p, 1), b = run(p, 2), c = run(p, 5);
  ASSERT_EQ(a.matches.size(), b.matches.size());
  ASSERT_EQ(a.matches.size(), c.matches.size());
  for (size_t k = 0; k < a.matches.size(); ++k) {
    EXPECT_EQ(a.matches[k].i1, b.matches[k].i1);
    EXPECT_EQ(a.matches[k].i2, b.matches[k].i2);
    EXPECT_EQ(a.matches[k].i2, c.matches[k].i2);
  }
}

// A copy of a true keypoint's descriptor 20 px along the epipolar line (repeated texture, e.g. a row
// of identical roofs): inside the ratio test's region, so the ambiguous match is rejected.
TEST(GuidedMatch, RatioTestSeesRepeatsAlongTheBand) {
  Pair p = make_pair(2000, 0, 3);
  const int victim = 100;
  bool found = false;
  for (const auto& m : run(p, 2).matches) found |= m.i1 == victim && m.i2 == victim;
  ASSERT_TRUE(found);  // matched without the twin
  const float c = std::cos(0.1745f), s = std::sin(0.1745f);
  cv::KeyPoint twin = p.K2.kp[victim];
  twin.pt.x += 20 * c;
  twin.pt.y += 20 * s;
  p.K2.kp.push_back(twin);
  p.K2.id.push_back(static_cast<long long>(p.K2.kp.size()) - 1);
  cv::Mat d = p.K2.desc.row(victim).clone();
  p.K2.desc.push_back(d);
  const GuidedMatchResult g = run(p, 2);
  ASSERT_TRUE(g.ok);
  for (const auto& m : g.matches) EXPECT_NE(m.i1, victim);
}

TEST(GuidedMatch, NoGeometryWithoutOverlap) {
  Pair p = make_pair(0, 2000, 4);
  EXPECT_FALSE(run(p, 2).ok);
}

TEST(KeypointCache, RoundTripAndStaleFiles) {
  const auto dir = std::filesystem::temp_directory_path() / ("tpkit_kpcache_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Pair p = make_pair(50, 0, 5);
  const std::string f = (dir / "a.sift").string();
  save_keypoints(f, "image=a detector=x", p.K1);
  Keypoints K;
  ASSERT_TRUE(load_keypoints(f, "image=a detector=x", K));
  ASSERT_EQ(K.kp.size(), p.K1.kp.size());
  for (size_t i = 0; i < K.kp.size(); ++i) {
    EXPECT_EQ(K.kp[i].pt, p.K1.kp[i].pt);
    EXPECT_EQ(K.kp[i].response, p.K1.kp[i].response);
    EXPECT_EQ(K.id[i], p.K1.id[i]);
  }
  EXPECT_EQ(cv::norm(K.desc, p.K1.desc, cv::NORM_INF), 0.0);
  EXPECT_FALSE(load_keypoints(f, "image=a detector=y", K));  // other options
  std::filesystem::resize_file(f, std::filesystem::file_size(f) - 10);
  EXPECT_FALSE(load_keypoints(f, "image=a detector=x", K));  // truncated
  EXPECT_FALSE(load_keypoints((dir / "none.sift").string(), "image=a detector=x", K));
  std::filesystem::remove_all(dir);
}

namespace {
std::string slurp_bytes(const std::string& f) {
  std::ifstream in(f, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
void spill_bytes(const std::string& f, const std::string& b) { std::ofstream(f, std::ios::binary) << b; }
}  // namespace

TEST(KeypointCache, UntrustedEntriesAreRefused) {
  // a cache file is input like any other: a flipped byte, a forged count, a non-finite value with a
  // valid checksum each count as missing (no crash, no giant allocation)
  const auto dir = std::filesystem::temp_directory_path() / ("tpkit_kpcache_bad_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Pair p = make_pair(50, 0, 5);
  const std::string f = (dir / "a.sift").string();
  const std::string id = "image=a detector=x";
  save_keypoints(f, id, p.K1);
  const std::string good = slurp_bytes(f);
  Keypoints K;
  ASSERT_TRUE(load_keypoints(f, id, K));

  std::string flipped = good;
  flipped[good.size() / 2] ^= 0x10;
  spill_bytes(f, flipped);
  EXPECT_FALSE(load_keypoints(f, id, K)) << "checksum";

  std::string forged = good;
  const std::string count = " count=" + std::to_string(p.K1.kp.size()) + "\n";
  forged.replace(forged.find(count), count.size(), " count=2147483647\n");
  spill_bytes(f, forged);
  EXPECT_FALSE(load_keypoints(f, id, K)) << "forged count";

  spill_bytes(f, std::string(100000, '\0'));
  EXPECT_FALSE(load_keypoints(f, id, K)) << "zeros";

  Keypoints nan = p.K1;
  nan.kp[3].pt.x = std::numeric_limits<float>::quiet_NaN();
  save_keypoints(f, id, nan);
  EXPECT_FALSE(load_keypoints(f, id, K)) << "NaN with a valid checksum";
  std::filesystem::remove_all(dir);
}

TEST(KeypointCache, LargeEntriesAreReadInChunksAndEveryByteIsChecked) {
  // 20001 records: read and hashed 8192 at a time (three chunks, the last of 3617 records, whose bytes
  // end in a part of 32 that is hashed byte by byte); a flipped bit anywhere in the records is refused
  const auto dir = std::filesystem::temp_directory_path() / ("tpkit_kpcache_big_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Pair p = make_pair(20001, 0, 6);
  const std::string f = (dir / "a.sift").string();
  const std::string id = "image=a detector=x";
  save_keypoints(f, id, p.K1);
  Keypoints K;
  ASSERT_TRUE(load_keypoints(f, id, K));
  ASSERT_EQ(K.kp.size(), p.K1.kp.size());
  for (size_t i = 0; i < K.kp.size(); ++i) {
    ASSERT_EQ(K.kp[i].pt, p.K1.kp[i].pt);
    ASSERT_EQ(K.id[i], p.K1.id[i]);
  }
  EXPECT_EQ(cv::norm(K.desc, p.K1.desc, cv::NORM_INF), 0.0);
  const std::string good = slurp_bytes(f);
  const size_t records = good.size() - 8 - 20001 * 164;  // where the records start
  // in the first chunk, in the second, in the last whole 32 bytes and in the bytes after them
  for (size_t at : {records + 100, records + 8192 * 164 + 5, good.size() - 8 - 40, good.size() - 8 - 3}) {
    std::string flipped = good;
    flipped[at] ^= 0x01;
    spill_bytes(f, flipped);
    EXPECT_FALSE(load_keypoints(f, id, K)) << "byte " << at;
  }
  std::filesystem::remove_all(dir);
}

// match_in_regions against the definition, written out with nothing shared: for every image-1
// keypoint, the exact integer L2 distance to every image-2 keypoint, which lie in its region and its
// wider region decided by the region's own frame; the nearest in the region, the ratio test against
// the second nearest in the wider region, and the mutual check over all the image-1 keypoints whose
// wider region holds the match (ties to the lower index). Descriptors mix 0s and 255s with random bytes,
// so that components differ by 255 (the largest square the vector code adds in pairs).
TEST(GuidedMatch, RegionSearchIsTheExactDefinition) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> pos(0, 400), unit(0, 1);
  std::uniform_int_distribution<int> byte(0, 255), pick(0, 3);
  const int n1 = 1200, n2 = 1500;
  Keypoints K1, K2;
  K1.desc.create(n1, 128, CV_8U);
  K2.desc.create(n2, 128, CV_8U);
  auto extreme_byte = [&] { const int c = pick(rng); return c == 0 ? 0 : c == 1 ? 255 : byte(rng); };
  for (int j = 0; j < n2; ++j) {
    K2.kp.emplace_back(static_cast<float>(pos(rng)), static_cast<float>(pos(rng)), 4.f);
    for (int k = 0; k < 128; ++k) K2.desc.at<uint8_t>(j, k) = static_cast<uint8_t>(extreme_byte());
  }
  std::vector<SearchRegion> regions(n1);
  for (int i = 0; i < n1; ++i) {
    K1.kp.emplace_back(static_cast<float>(pos(rng)), static_cast<float>(pos(rng)), 4.f);
    // most keypoints near a copy of an image-2 descriptor with a few bytes flipped between 0 and 255
    const int src = i % n2;
    for (int k = 0; k < 128; ++k) {
      int v = K2.desc.at<uint8_t>(src, k);
      if (unit(rng) < 0.04 + 0.3 * (i % 3 == 0)) v = 255 - v;
      K1.desc.at<uint8_t>(i, k) = static_cast<uint8_t>(v);
    }
    const double a = 0.2 + 0.1 * unit(rng);  // directions near one another, as along epipolar curves
    SearchRegion& R = regions[i];
    R.u = Eigen::Vector2d(std::cos(a), std::sin(a));
    R.length = i % 50 == 0 ? -1 : 5 + 40 * unit(rng);
    R.band = 1 + 3 * unit(rng);
    const Eigen::Vector2d x2(K2.kp[src].pt.x, K2.kp[src].pt.y), n(R.u.y(), -R.u.x());
    R.a = x2 - R.length * unit(rng) * R.u + (unit(rng) - 0.5) * R.band * n;
  }
  DescriptorMatchOptions desc;
  const double margin = 24;
  // the definition
  auto dist = [&](int i, int j) {
    int s = 0;
    for (int k = 0; k < 128; ++k) {
      const int d = K1.desc.at<uint8_t>(i, k) - K2.desc.at<uint8_t>(j, k);
      s += d * d;
    }
    return s;
  };
  auto where = [&](int i, int j, bool wide) {
    const SearchRegion& R = regions[i];
    const double vx = K2.kp[j].pt.x - R.a.x(), vy = K2.kp[j].pt.y - R.a.y();
    const double across = R.u.y() * vx - R.u.x() * vy, along = R.u.x() * vx + R.u.y() * vy;
    const double w = wide ? margin : 0;
    return std::abs(across) <= R.band + w && along >= -w && along <= R.length + w;
  };
  std::vector<std::pair<int, int>> nearest_of_j(n2, {INT_MAX, -1});  // (distance, i)
  std::vector<std::array<int, 3>> fwd;                                  // i, j, distance
  for (int i = 0; i < n1; ++i) {
    if (regions[i].length < 0) continue;
    std::pair<int, int> acc{INT_MAX, -1}, m1{INT_MAX, -1}, m2{INT_MAX, -1};
    for (int j = 0; j < n2; ++j) {
      if (!where(i, j, true)) continue;
      const std::pair<int, int> d{dist(i, j), j};
      if (d < m1) m2 = m1, m1 = d;
      else if (d < m2) m2 = d;
      if (where(i, j, false) && d < acc) acc = d;
      nearest_of_j[j] = std::min(nearest_of_j[j], std::pair<int, int>{d.first, i});
    }
    if (acc.second < 0) continue;
    const std::pair<int, int> second = m1.second == acc.second ? m2 : m1;
    const float ratio2 = static_cast<float>(desc.ratio * desc.ratio);
    if (second.second >= 0 && !(static_cast<float>(acc.first) < ratio2 * static_cast<float>(second.first))) continue;
    fwd.push_back({i, acc.second, acc.first});
  }
  std::vector<std::array<int, 3>> want;
  for (const auto& f : fwd)
    if (nearest_of_j[f[1]].second == f[0]) want.push_back(f);
  ASSERT_GT(want.size(), 300u);  // enough matches to mean something
  for (int threads : {1, 3}) {
    const RegionMatchResult got = match_in_regions(K1, K2, regions, desc, margin, threads);
    ASSERT_EQ(got.matches.size(), want.size()) << threads << " threads";
    for (size_t k = 0; k < want.size(); ++k) {
      EXPECT_EQ(got.matches[k].i1, want[k][0]);
      EXPECT_EQ(got.matches[k].i2, want[k][1]);
      EXPECT_EQ(got.matches[k].distance, std::sqrt(static_cast<float>(want[k][2])));
    }
  }
}
