// bench_chain: time and peak memory of tp-chain on the matches of every pair of a block (issue 24).
//
// Makes a block of N images (default 6) and P ground points, each seen in every image with probability
// 0.6 (at least two), matched in every pair of its views (so one point of k views gives k(k-1)/2
// records, and every keypoint is shared by k-1 records, as tp-match's files of a block are), writes the
// matches files as tp-match writes them (id1 x1 y1 id2 x2 y2 kx2 ky2 sigma corr) until --matches
// records are written in all, then runs tp-chain on them as a child process and prints its wall time
// and peak resident memory (getrusage of the child), per match, and checks the tracks it wrote against
// the truth: every point one track with exactly its views.
//   usage: bench_chain [--matches N] [--images N] [--seed S] [--tp-chain PATH] [--keep DIR]
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "tpkit/core/formats.hpp"

namespace fs = std::filesystem;

namespace {
[[noreturn]] void usage(int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: bench_chain [--matches N] [--images N] [--seed S] [--tp-chain PATH] [--keep DIR]\n"
               "  the matches of every pair of a synthetic block of N images (default 6), --matches records in all\n"
               "  (default 3000000), chained by tp-chain (default: beside this program): wall time, peak memory\n");
  std::exit(code);
}

long number(const char* opt, const char* v) {
  char* end = nullptr;
  const long n = std::strtol(v, &end, 10);
  if (!*v || *end || n <= 0) {
    std::fprintf(stderr, "bench_chain: %s: not a positive whole number: '%s'\n", opt, v);
    std::exit(2);
  }
  return n;
}
}  // namespace

int main(int argc, char** argv) {
  long target = 3000000, images = 6, seed = 1;
  std::string tool = (fs::path(argv[0]).parent_path() / "tp-chain").string(), keep;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") usage(0);
    if (i + 1 >= argc) usage(2);
    if (a == "--matches") target = number("--matches", argv[++i]);
    else if (a == "--images") images = number("--images", argv[++i]);
    else if (a == "--seed") seed = number("--seed", argv[++i]);
    else if (a == "--tp-chain") tool = argv[++i];
    else if (a == "--keep") keep = argv[++i];
    else usage(2);
  }
  if (images < 2) {
    std::fprintf(stderr, "bench_chain: --images: at least 2\n");
    return 2;
  }
  const fs::path dir = keep.empty() ? fs::temp_directory_path() / ("bench-chain-" + std::to_string(::getpid())) : fs::path(keep);
  fs::create_directories(dir);
  const int N = static_cast<int>(images);

  // the block: points until the records reach the target; per image a keypoint id per point seen
  std::mt19937_64 rng(static_cast<unsigned long long>(seed));
  std::uniform_real_distribution<double> J(0, 1), S(0.02, 0.2);
  std::bernoulli_distribution sees(0.6);
  std::map<std::pair<int, int>, tpkit::Matches> pairs;
  for (int i = 0; i < N; ++i)
    for (int j = i + 1; j < N; ++j) {
      tpkit::Matches& m = pairs[{i, j}];
      m.image1 = {"view_" + std::to_string(i + 1) + ".tif", 10000, 10000};
      m.image2 = {"view_" + std::to_string(j + 1) + ".tif", 10000, 10000};
    }
  struct Rec {
    long long id1, id2;
    double x1, y1, x2, y2, sigma;
  };
  std::map<std::pair<int, int>, std::vector<Rec>> recs;
  std::vector<long long> next_id(static_cast<size_t>(N), 0);
  std::map<int, long> truth_by_length;
  long records = 0, points = 0;
  std::vector<int> v;
  std::vector<long long> id(static_cast<size_t>(N));
  std::vector<double> x(static_cast<size_t>(N)), y(static_cast<size_t>(N));
  while (records < target) {
    v.clear();
    for (int i = 0; i < N; ++i)
      if (sees(rng)) v.push_back(i);
    if (v.size() < 2) continue;
    // keypoint k of an image in its own cell of a 2.5 px grid (4000 a row), jittered by up to 1 px: no
    // two keypoints of one image within tp-chain's --same-position, so the truth stays the truth
    for (int i : v) {
      const long long k = next_id[static_cast<size_t>(i)]++;
      id[static_cast<size_t>(i)] = k;
      x[static_cast<size_t>(i)] = 2.5 * static_cast<double>(k % 4000) + J(rng);
      y[static_cast<size_t>(i)] = 2.5 * static_cast<double>(k / 4000) + J(rng);
    }
    for (size_t a = 0; a < v.size(); ++a)
      for (size_t b = a + 1; b < v.size(); ++b) {
        const size_t i = static_cast<size_t>(v[a]), j = static_cast<size_t>(v[b]);
        recs[{v[a], v[b]}].push_back({id[i], id[j], x[i], y[i], x[j], y[j], S(rng)});
        ++records;
      }
    truth_by_length[static_cast<int>(v.size())]++;
    ++points;
  }
  std::vector<std::string> files;
  for (auto& [key, m] : pairs) {
    const auto& rs = recs[key];
    m.xy.resize(static_cast<Eigen::Index>(rs.size()), 4);
    m.extra.names = {"kx2", "ky2", "sigma", "corr"};
    m.extra.values.resize(static_cast<Eigen::Index>(rs.size()), 4);
    for (size_t r = 0; r < rs.size(); ++r) {
      const Eigen::Index e = static_cast<Eigen::Index>(r);
      m.id1.push_back(rs[r].id1);
      m.id2.push_back(rs[r].id2);
      m.xy.row(e) << rs[r].x1, rs[r].y1, rs[r].x2 + 0.01, rs[r].y2 - 0.01;
      m.extra.values.row(e) << rs[r].x2, rs[r].y2, rs[r].sigma, 0.95;
    }
    const std::string f = (dir / ("pair-" + std::to_string(key.first + 1) + "-" + std::to_string(key.second + 1) + ".matches")).string();
    tpkit::save_matches(f, m);
    files.push_back(f);
    recs[key].clear();
    recs[key].shrink_to_fit();
    m = tpkit::Matches();
  }
  std::printf("block: %d images, %ld points, %ld matches in %zu files\n", N, points, records, files.size());
  std::printf("truth tracks by views:");
  for (const auto& kv : truth_by_length) std::printf(" %d:%ld", kv.first, kv.second);
  std::printf("\n");
  std::fflush(stdout);

  // tp-chain as a child: its own peak memory
  const std::string out = (dir / "block.tracks").string();
  std::vector<std::string> args = {tool, "-q", "-o", out};
  args.insert(args.end(), files.begin(), files.end());
  std::vector<char*> cargs;
  for (auto& s : args) cargs.push_back(s.data());
  cargs.push_back(nullptr);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    execv(cargs[0], cargs.data());
    std::perror("bench_chain: exec tp-chain");
    _exit(127);
  }
  int status = 0;
  struct rusage ru {};
  wait4(pid, &status, 0, &ru);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "bench_chain: tp-chain failed (status %d)\n", status);
    return 1;
  }
  const double peak = static_cast<double>(ru.ru_maxrss) * 1024.0;
  std::printf("tp-chain: wall %.2f s, user %.2f s, peak memory %.1f MB = %.1f bytes per match\n", wall,
              static_cast<double>(ru.ru_utime.tv_sec) + 1e-6 * static_cast<double>(ru.ru_utime.tv_usec), peak / 1e6,
              peak / static_cast<double>(records));

  // the tracks against the truth: counts by length
  const tpkit::Tracks t = tpkit::read_tracks(out);
  std::map<int, long> by_length;
  for (size_t r = 0; r < t.size(); ++r) by_length[t.seen_views(r)]++;
  std::printf("tracks by views:");
  for (const auto& kv : by_length) std::printf(" %d:%ld", kv.first, kv.second);
  const bool ok = by_length == truth_by_length;
  std::printf(" (%s the truth)\n", ok ? "equal to" : "DIFFERENT FROM");
  if (keep.empty()) fs::remove_all(dir);
  return ok ? 0 : 1;
}
