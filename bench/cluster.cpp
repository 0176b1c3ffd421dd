// Benchmark of cluster-homog's library (issue 6): success rates, iterations and times on the paper's
// setup (Navy et al. 2005, section 6), robustness to extra/missing points, the correspondence-free
// search, and time against the cluster size. Prints plain tables on stdout.
//
//   bench_cluster [--trials N] [--section paper|robust|scratch|verdict|families|unrelated|few|scale|all] [--max-n N]
//                 [--family K] [--n N [--first T]] [--paper-cost] [--model auto|similarity|affine|homography] [--verbose]
//
// --model: the model of the families', the unrelated pairs' and the few-points cases' solves, as
// cluster-homog --model (cluster_solve.hpp; default auto, the tool's default). --section few: astroalign's
// TestFewSources (2 to 6 stars at integer positions under a 50 degree rotation and a (10, -20) shift in a
// 512 x 512 frame; 2 must be refused), random similarities of 3 to 6 such stars, and unrelated
// 3 to 6 stars (false accepts).
//
// --family K runs only the K-th family (1-based) of --section families (the one after the last: the
// unrelated pairs); --n N runs --section unrelated at N points only, with --trials trials (a 95% bound of
// 0.1% on false accepts needs 3000 trials without one; --first T starts at trial T, whose seeds are
// fixed, so the 3000 can be split over processes and the counts added); --paper-cost makes the
// families and unrelated pairs use the paper's untrimmed cost instead of cluster-homog's default (the
// trim chosen from the data, cluster_cost.hpp), which was the default before.
//
// Clusters: A = n points uniform in [0, 512]^2 pixels (image 1), B = h(A) (+ noise), h = eq. 4 as the
// section 4 model gives it (physical_homography.hpp). Success: final cost <= 0.25 px and h within
// 0.5 px of the truth on a 5 x 5 grid over A's bounding box ("h ok" counts the second part alone).
// Times: CPU time of the calling thread (the machine may be shared) and wall time.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "tpkit/cluster/cluster_cost.hpp"
#include "tpkit/cluster/cluster_optimize.hpp"
#include "tpkit/cluster/cluster_search.hpp"
#include "tpkit/cluster/cluster_solve.hpp"
#include "tpkit/cluster/cluster_synth.hpp"
#include "tpkit/cluster/cluster_verdict.hpp"
#include "tpkit/cluster/physical_homography.hpp"

using namespace tpkit;

namespace {

bool g_paper_cost = false;  // --paper-cost
bool g_verbose = false;     // --verbose: the failed trials of the families on stderr
std::string g_model = "auto";  // --model
// cluster-homog's default cost: the trim chosen from the data (or the paper's cost with --paper-cost)
CostOptions tool_default_cost() {
  CostOptions co;
  co.trim_from_data = !g_paper_cost;
  return co;
}

// What cluster-homog does from scratch with --model g_model (math parameterization): the chosen map and
// its verdict. domain: the field of B (its image's area; 0: hull B).
struct ToolAnswer {
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
  Verdict verdict;
  long hypotheses = 0;
  std::string method;
};
ToolAnswer solve_as_tool(const ClusterCost& cost, uint64_t seed, double domain = 0) {
  SolveOptions so;
  so.optimize.param = Parameterization::Math;
  so.optimize.seed = seed;
  so.automatic = g_model == "auto";
  so.model = g_model == "similarity" ? ClusterModel::Similarity : g_model == "affine" ? ClusterModel::Affine : ClusterModel::Homography;
  so.domain_area_b = domain;
  const ClusterSolution sol = solve_clusters(cost, OptimizeStart{}, so);
  return {sol.chosen.H, sol.chosen.verdict, sol.hypotheses,
          std::string(cluster_model_name(sol.chosen.model)) + ", " + sol.chosen.method};
}

double cpu_now() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

struct Stats {
  int trials = 0, ok = 0, h_ok = 0;
  double iters = 0, evals = 0, secs = 0, worst_secs = 0, cpu = 0, worst_cpu = 0;
  std::vector<double> it_ok, final_cost;
};

void run_case(const char* label, int trials, const ClusterSynthOptions& base, const OptimizeOptions& oo,
              CostOptions co, bool with_init) {
  Stats s;
  Eigen::Matrix3d truth = physical_homography(paper_physical_params());
  for (int t = 0; t < trials; ++t) {
    ClusterSynthOptions so = base;
    so.seed = 1000 + static_cast<uint64_t>(t);
    ClusterPair cp = synth_cluster_pair(truth, so);
    ClusterCost cost(cp.A, cp.B, co);
    OptimizeStart st;
    if (with_init) {
      st.has_physical = true;
      st.physical = paper_start_params();
    }
    OptimizeOptions o = oo;
    o.seed = static_cast<uint64_t>(t + 1);
    double c0 = cpu_now();
    OptimizeResult r = optimize_clusters(cost, st, o);
    double cpu = cpu_now() - c0;
    double diff = homography_max_difference(r.H, truth, extent_grid(cp.A));
    bool ok = r.cost <= 0.25 && diff <= 0.5;
    s.trials++;
    s.ok += ok;
    s.h_ok += diff <= 0.5;
    s.cpu += cpu;
    s.worst_cpu = std::max(s.worst_cpu, cpu);
    s.iters += static_cast<double>(r.iterations);
    s.evals += static_cast<double>(r.evaluations);
    s.secs += r.seconds;
    s.worst_secs = std::max(s.worst_secs, r.seconds);
    s.final_cost.push_back(r.cost);
    if (ok) s.it_ok.push_back(static_cast<double>(r.iterations));
  }
  std::sort(s.it_ok.begin(), s.it_ok.end());
  double med = s.it_ok.empty() ? 0 : s.it_ok[s.it_ok.size() / 2];
  std::sort(s.final_cost.begin(), s.final_cost.end());
  double medc = s.final_cost.empty() ? 0 : s.final_cost[s.final_cost.size() / 2];
  std::printf("%-46s %4d/%-4d %6.1f%% (h ok %3d)  cost median %6.3f  iter mean %6.0f  median(ok) %6.0f  evals %7.0f  cpu mean %7.2f ms max %7.2f ms  wall mean %7.2f ms\n",
              label, s.ok, s.trials, 100.0 * s.ok / std::max(1, s.trials), s.h_ok, medc, s.iters / s.trials, med,
              s.evals / s.trials, 1e3 * s.cpu / s.trials, 1e3 * s.worst_cpu, 1e3 * s.secs / s.trials);
  std::fflush(stdout);
}

// The verdict (cluster_verdict.hpp) on related pairs (B = h(A) + noise, extra/missing points, found from
// scratch): accepted and right (h within 0.5 px over A's extent), accepted and wrong (the worst case),
// rejected; and on unrelated pairs (A and B independent uniform clusters of n points): false accepts.
void verdict_case(const char* label, int trials, const ClusterSynthOptions& base, CostOptions co) {
  int right = 0, wrong = 0, rejected = 0;
  Eigen::Matrix3d truth = physical_homography(paper_physical_params());
  for (int t = 0; t < trials; ++t) {
    ClusterSynthOptions so = base;
    so.seed = 5000 + static_cast<uint64_t>(t);
    ClusterPair cp = synth_cluster_pair(truth, so);
    ClusterCost cost(cp.A, cp.B, co);
    OptimizeOptions o;
    o.param = Parameterization::Math;
    o.seed = static_cast<uint64_t>(t + 1);
    OptimizeResult r = optimize_clusters(cost, OptimizeStart{}, o);
    VerdictOptions vo;
    vo.hypotheses = std::max(1L, r.evaluations);
    const Verdict v = judge_homography(cost, r.H, vo);
    const bool h_ok = homography_max_difference(r.H, truth, extent_grid(cp.A)) <= 0.5;
    if (!v.accepted) ++rejected;
    else if (h_ok) ++right;
    else ++wrong;
  }
  std::printf("%-52s %4d trials: accepted right %5.1f%%, accepted WRONG %5.1f%%, rejected %5.1f%%\n", label, trials,
              100.0 * right / trials, 100.0 * wrong / trials, 100.0 * rejected / trials);
  std::fflush(stdout);
}

// Star-field-like families (issue 15): B = h(A) with h from random_family_homography (cluster_synth.hpp:
// any rotation, scale 0.3..3, anisotropy up to `aniso`, projective terms up to `proj`), noise 0.1 px; a
// fraction `unmatched` of each cluster's points without a partner (cluster A: n + unmatched n points, of
// which n (1 - unmatched) have a partner; B: n points).
// Found from scratch (default optimizer, math). Success: accepted, and h within 0.5 px RMS of the truth
// over A's 5 x 5 extent grid.
void family_case(const char* label, int n, double aniso, double proj, double unmatched, int trials) {
  int ok = 0, wrong = 0, rejected = 0, n_determined = 0, ok_determined = 0;
  int mismatched = 0;  // accepted wrong, and far (> 1 px) from the oracle too: wrong correspondences
  double secs = 0;
  std::vector<double> rms_all;
  for (int t = 0; t < trials; ++t) {
    const double ext = 512;
    const Eigen::Matrix3d H = random_family_homography(aniso, proj, ext, 4242 + 1000003ULL * static_cast<uint64_t>(n) + static_cast<uint64_t>(t));
    ClusterSynthOptions so;
    so.n = n, so.extent = ext, so.noise = 0.1, so.seed = 70000 + static_cast<uint64_t>(t);
    so.extra = unmatched, so.missing = unmatched;
    ClusterPair cp = synth_cluster_pair(H, so);
    ClusterCost cost(cp.A, cp.B, tool_default_cost());
    OptimizeOptions o;
    o.param = Parameterization::Math;
    o.seed = static_cast<uint64_t>(t + 1);
    const auto t0 = std::chrono::steady_clock::now();
    ToolAnswer r;
    bool accepted = false;
    try {
      r = solve_as_tool(cost, o.seed);
      accepted = r.verdict.accepted;
    } catch (const std::exception&) {
    }
    secs += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double rms = homography_rms_difference(r.H, cp.truth, extent_grid(cp.A));  // image 2 pixels
    rms_all.push_back(rms);
    const bool h_ok = rms <= 0.5;
    if (g_verbose && !(accepted && h_ok))
      std::fprintf(stderr, "%s: trial %d failed: %s, h error %.3g px, %s\n", label, t, accepted ? "accepted" : "rejected", rms,
                   r.method.c_str());
    // determined: the oracle (least squares on the true correspondences: the maximum-likelihood h, the
    // best any search can return) passes the verdict with the same number of tests and lies within
    // 0.5 px RMS of the truth; 4 points never pass, 5 or 6 points not always (few matches beyond the 4
    // fitted ones to verify; a few noisy points do not pin h down to 0.5 px over the whole extent)
    std::vector<std::pair<int, int>> truth_pairs;
    for (const MutualPair& mp : mutual_pairs(cost, cp.truth))
      if (mp.d <= 1) truth_pairs.emplace_back(mp.ia, mp.ib);
    VerdictOptions vo;
    vo.hypotheses = std::max(1L, r.hypotheses);
    const Eigen::Matrix3d oracle = fit_on_pairs(cost, cp.truth, truth_pairs);
    const bool determined = judge_homography(cost, oracle, vo).accepted &&
                            homography_rms_difference(oracle, cp.truth, extent_grid(cp.A)) <= 0.5;
    n_determined += determined;
    if (!accepted) ++rejected;
    else if (h_ok) ++ok, ok_determined += determined;
    else ++wrong, mismatched += homography_rms_difference(r.H, oracle, extent_grid(cp.A)) > 1;
  }
  std::sort(rms_all.begin(), rms_all.end());
  std::printf("%-58s %4d trials: success %5.1f%%, accepted WRONG %4.1f%%, rejected %5.1f%%, median h error %.3g px, %.2f s each;"
              " determined %5.1f%%, success of those %5.1f%%; wrong correspondences %4.1f%%\n",
              label, trials, 100.0 * ok / trials, 100.0 * wrong / trials, 100.0 * rejected / trials,
              rms_all[rms_all.size() / 2], secs / trials, 100.0 * n_determined / trials,
              n_determined ? 100.0 * ok_determined / n_determined : 0.0, 100.0 * mismatched / trials);
  std::fflush(stdout);
}

void unrelated_case(int n, int trials, int first = 0) {
  int accepted = 0;
  std::vector<double> odds;  // the verdict's log10 odds of each trial
  const auto t0 = std::chrono::steady_clock::now();
  for (int t = first; t < first + trials; ++t) {
    ClusterSynthOptions sa;
    sa.n = n;
    sa.seed = 9000 + static_cast<uint64_t>(t);
    ClusterSynthOptions sb = sa;
    sb.seed = 19000 + static_cast<uint64_t>(t);
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    ClusterCost cost(synth_cluster_pair(I, sa).A, synth_cluster_pair(I, sb).A, tool_default_cost());
    OptimizeOptions o;
    o.param = Parameterization::Math;
    o.seed = static_cast<uint64_t>(t + 1);
    try {
      const Verdict v = solve_as_tool(cost, o.seed).verdict;
      accepted += v.accepted;
      odds.push_back(v.log10_odds);
    } catch (const std::exception&) {  // no usable hypothesis at all: no answer, so no false accept
      odds.push_back(-std::numeric_limits<double>::infinity());
    }
  }
  std::sort(odds.begin(), odds.end());
  // the 95% upper bound of the rate: the rule of three when none was accepted, else Wilson's
  const double p = static_cast<double>(accepted) / trials, z = 1.96;
  const double upper = accepted == 0 ? 3.0 / trials
                                     : (p + z * z / (2 * trials) + z * std::sqrt(p * (1 - p) / trials + z * z / (4.0 * trials * trials))) /
                                           (1 + z * z / trials);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("unrelated uniform clusters, n = %-5d trials %4d-%-4d: false accepts %d of %d (%.2f%%, 95%% upper bound %.2f%%), "
              "log10 odds median %.1f, 99th percentile %.1f, max %.1f (accepted at 3), %.2f s each\n",
              n, first, first + trials - 1, accepted, trials, 100.0 * accepted / trials, 100.0 * upper, odds[odds.size() / 2],
              odds[std::min(odds.size() - 1, odds.size() * 99 / 100)], odds.back(), secs / trials);
  std::fflush(stdout);
}

// Stars at integer pixels as astroalign's simulate_image_pair gives them: the reference positions
// shifted by the crop (-5, -5); the new ones rotated by `angle` about the frame centre (256, 256), shifted
// by (tx, ty), truncated to integers and cropped likewise. B is shuffled; the truth is the generating map
// followed by the truncation's mean shift.
struct StarPair {
  Eigen::MatrixX2d A, B;
  Eigen::Matrix3d truth;
};
StarPair star_pair(const std::vector<Eigen::Vector2d>& ref, double angle, double scale, double tx, double ty, uint64_t seed) {
  const double c = scale * std::cos(angle), s = scale * std::sin(angle);
  Eigen::Matrix3d T0, R, T1, crop;
  T0 << 1, 0, -256, 0, 1, -256, 0, 0, 1;
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  T1 << 1, 0, 256 + tx, 0, 1, 256 + ty, 0, 0, 1;
  crop << 1, 0, -5, 0, 1, -5, 0, 0, 1;
  StarPair sp;
  const Eigen::Matrix3d M = T1 * R * T0;  // uncropped reference -> uncropped new
  // truncation moves a new star by -0.5 px per axis on average: the truth includes that shift
  Eigen::Matrix3d bias;
  bias << 1, 0, -0.5, 0, 1, -0.5, 0, 0, 1;
  sp.truth = bias * crop * M * crop.inverse();
  const int n = static_cast<int>(ref.size());
  sp.A.resize(n, 2), sp.B.resize(n, 2);
  std::vector<int> order(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) order[static_cast<size_t>(i)] = i;
  std::mt19937_64 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d& p = ref[static_cast<size_t>(i)];
    sp.A.row(i) << p.x() - 5, p.y() - 5;
    const Eigen::Vector3d q = M * Eigen::Vector3d(p.x(), p.y(), 1);
    sp.B.row(order[static_cast<size_t>(i)]) << std::trunc(q.x()) - 5, std::trunc(q.y()) - 5;
  }
  return sp;
}

// One few-stars case: refused (fewer points than a model needs), accepted within 1 px of the truth over
// A's points (astroalign's tolerance on the translation), accepted within 3 px (imprecise: the integer
// positions' +-0.5 px on 3 stars), accepted wrong (further: other correspondences), or rejected.
enum class FewOutcome { Refused, Right, Imprecise, Wrong, Rejected };
FewOutcome few_case(const StarPair& sp, std::string* what = nullptr) {
  try {
    const ClusterModel least = g_model == "auto" || g_model == "similarity" ? ClusterModel::Similarity
                               : g_model == "affine"                       ? ClusterModel::Affine
                                                                           : ClusterModel::Homography;
    validate_cluster(sp.A, "A", least);
    validate_cluster(sp.B, "B", least);
  } catch (const std::exception& e) {
    if (what) *what = e.what();
    return FewOutcome::Refused;
  }
  ClusterCost cost(sp.A, sp.B, tool_default_cost());
  ToolAnswer r;
  try {
    r = solve_as_tool(cost, 1, 512.0 * 512.0);
  } catch (const std::exception& e) {
    if (what) *what = e.what();
    return FewOutcome::Rejected;
  }
  const double err = homography_max_difference(r.H, sp.truth, sp.A);
  if (what) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s, log10 odds %.2f, %d of %d matched within %.3f px, max error at A's points %.3f px",
                  r.method.c_str(), r.verdict.log10_odds, r.verdict.inliers, r.verdict.candidates, r.verdict.radius_px, err);
    *what = buf;
  }
  if (!r.verdict.accepted) return FewOutcome::Rejected;
  return err <= 1 ? FewOutcome::Right : err <= 3 ? FewOutcome::Imprecise : FewOutcome::Wrong;
}

void few_section(int trials) {
  const std::vector<Eigen::Vector2d> stars = {{100, 150}, {120, 200}, {400, 200}, {400, 320}, {200, 210}, {200, 350}};
  const double kPi = 3.14159265358979323846;
  std::printf("== few stars (astroalign TestFewSources), --model %s, field 512 x 512\n", g_model.c_str());
  int passed = 0;
  for (int n = 2; n <= 6; ++n) {
    const std::vector<Eigen::Vector2d> ref(stars.begin(), stars.begin() + n);
    std::string what;
    const FewOutcome out = few_case(star_pair(ref, 50 * kPi / 180, 1, 10, -20, 77 + static_cast<uint64_t>(n)), &what);
    const bool pass = n == 2 ? out == FewOutcome::Refused : out == FewOutcome::Right;
    passed += pass;
    std::printf("astroalign %d stars: %s (%s)\n", n,
                out == FewOutcome::Refused     ? "refused"
                : out == FewOutcome::Right     ? "accepted, right"
                : out == FewOutcome::Imprecise ? "accepted, imprecise"
                : out == FewOutcome::Wrong     ? "accepted WRONG"
                                               : "rejected",
                what.c_str());
  }
  std::printf("astroalign cases passed: %d of 5 (2 stars must be refused); as its 10 tests (find_transform and register on the same positions): %d of 10\n",
              passed, 2 * passed);
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(0, 1);
  for (int n = 3; n <= 6; ++n) {
    int right = 0, imprecise = 0, wrong = 0, rejected = 0, false_accepts = 0;
    for (int t = 0; t < trials; ++t) {
      // stars uniform in the central 400 x 400 of the frame, a random rotation, scale 0.8..1.25, a shift
      // of up to 40 px: they stay in the frame
      std::vector<Eigen::Vector2d> ref;
      for (int i = 0; i < n; ++i) ref.emplace_back(56 + std::floor(400 * u(rng)), 56 + std::floor(400 * u(rng)));
      const double angle = 2 * kPi * u(rng), scale = std::exp(std::log(0.8) + (std::log(1.25) - std::log(0.8)) * u(rng));
      std::string what;
      const FewOutcome out = few_case(star_pair(ref, angle, scale, 80 * u(rng) - 40, 80 * u(rng) - 40, rng()), &what);
      if (g_verbose && out != FewOutcome::Right) std::fprintf(stderr, "%d stars, trial %d: %s\n", n, t, what.c_str());
      right += out == FewOutcome::Right, imprecise += out == FewOutcome::Imprecise, wrong += out == FewOutcome::Wrong;
      rejected += out == FewOutcome::Rejected || out == FewOutcome::Refused;
      // unrelated: two independent draws of n stars over the frame
      StarPair un;
      un.A.resize(n, 2), un.B.resize(n, 2);
      for (int i = 0; i < n; ++i) {
        un.A.row(i) << std::floor(507 * u(rng)), std::floor(507 * u(rng));
        un.B.row(i) << std::floor(507 * u(rng)), std::floor(507 * u(rng));
      }
      un.truth = Eigen::Matrix3d::Identity();
      const FewOutcome o2 = few_case(un);
      false_accepts += o2 == FewOutcome::Right || o2 == FewOutcome::Imprecise || o2 == FewOutcome::Wrong;
    }
    std::printf("random similarities, %d stars, %d trials: right (<= 1 px) %d, imprecise (1-3 px) %d, accepted WRONG %d, rejected %d;"
                " unrelated %d stars: false accepts %d of %d\n",
                n, trials, right, imprecise, wrong, rejected, n, false_accepts, trials);
  }
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  int trials = 100;
  long max_n = 100000;
  std::string section = "all";
  int family = 0;
  int only_n = 0;  // --n: the unrelated section at this size only, --trials trials
  int first = 0;   // --first: the first trial's index (its seeds), so one size can be split over processes
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--trials") && i + 1 < argc) trials = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--family") && i + 1 < argc) family = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--n") && i + 1 < argc) only_n = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--first") && i + 1 < argc) first = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--paper-cost")) g_paper_cost = true;
    else if (!std::strcmp(argv[i], "--verbose")) g_verbose = true;
    else if (!std::strcmp(argv[i], "--section") && i + 1 < argc) section = argv[++i];
    else if (!std::strcmp(argv[i], "--model") && i + 1 < argc) g_model = argv[++i];
    else if (!std::strcmp(argv[i], "--max-n") && i + 1 < argc) max_n = std::atol(argv[++i]);
    else {
      const bool help = !std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h");
      std::fprintf(help ? stdout : stderr, "usage: bench_cluster [--trials N] [--section paper|robust|scratch|verdict|families|unrelated|few|scale|all] [--max-n N] [--family K] [--n N [--first T]] [--paper-cost] [--model auto|similarity|affine|homography] [--verbose]\n");
      return help ? 0 : 2;
    }
  }
  if (first < 0 || (first > 0 && (only_n <= 0 || section != "unrelated"))) {
    std::fprintf(stderr, "bench_cluster: --first %d: needs --section unrelated --n N and a trial index >= 0\n", first);
    return 2;
  }
  if (g_model != "auto" && g_model != "similarity" && g_model != "affine" && g_model != "homography") {
    std::fprintf(stderr, "bench_cluster: --model %s: auto, similarity, affine or homography\n", g_model.c_str());
    return 2;
  }
  bool all = section == "all";
  ClusterSynthOptions paper;  // 100 points in [0, 512]^2, exact h
  OptimizeOptions o;
  if (all || section == "paper") {
    std::printf("== paper setup: n=100, h = eq. 4, start P1+(200,-50) m, alpha1-0.17, beta1-0.05, gamma1+0.5, noise 0\n");
    o.optimizer = OptimizerKind::Random;
    o.param = Parameterization::Physical;
    run_case("random (paper s6), physical, 12 free", trials, paper, o, {}, true);
    o.param = Parameterization::Math;
    run_case("random (paper s6), math", trials, paper, o, {}, true);
    ClusterSynthOptions small = paper;
    small.extent = 128;
    o.param = Parameterization::Physical;
    run_case("random (paper s6), physical, extent 128 px", trials, small, o, {}, true);
    o.optimizer = OptimizerKind::Default;
    o.param = Parameterization::Physical;
    run_case("default, physical, 12 free", trials, paper, o, {}, true);
    o.free_intrinsics = true;
    run_case("default, physical, 20 free", trials, paper, o, {}, true);
    o.free_intrinsics = false;
    o.param = Parameterization::Math;
    run_case("default, math", trials, paper, o, {}, true);
    ClusterSynthOptions noisy = paper;
    noisy.noise = 0.1;
    o.param = Parameterization::Physical;
    run_case("default, physical, noise 0.1 px", trials, noisy, o, {}, true);
  }
  if (all || section == "robust") {
    std::printf("== robustness: 20%% extra points in each cluster, 30%% missing from B, noise 0.1 px, --trim 0.45\n");
    ClusterSynthOptions rb = paper;
    rb.extra = 0.2, rb.missing = 0.3, rb.noise = 0.1;
    CostOptions trim{0.45, 0};
    o.optimizer = OptimizerKind::Default;
    o.param = Parameterization::Physical;
    run_case("default, physical, with init", trials, rb, o, trim, true);
    o.param = Parameterization::Math;
    run_case("default, math, with init", trials, rb, o, trim, true);
  }
  if (all || section == "scratch") {
    std::printf("== from scratch (no init): default optimizer = correspondence-free search + local refinement\n");
    ClusterSynthOptions sc = paper;
    sc.noise = 0.1;
    o.optimizer = OptimizerKind::Default;
    o.param = Parameterization::Math;
    run_case("scratch, eq. 4, noise 0.1 px", trials, sc, o, {}, false);
    run_case("scratch, eq. 4, noise 0.1 px, --trim 0.1", trials, sc, o, {0.1, 0}, false);
    sc.extra = 0.2, sc.missing = 0.3;
    run_case("scratch, + 20% extra / 30% missing, --trim 0.45", trials, sc, o, {0.45, 0}, false);
  }
  if (all || section == "verdict") {
    std::printf("== verdict: related pairs found from scratch, and unrelated pairs (false accepts)\n");
    ClusterSynthOptions v = paper;
    v.noise = 0.1;
    verdict_case("eq. 4, n=100, noise 0.1 px", trials, v, {});
    v.extra = 0.2, v.missing = 0.3;
    verdict_case("eq. 4, n=100, 20% extra, 30% missing, --trim 0.45", trials, v, {0.45, 0});
    v.n = 20, v.extra = 0, v.missing = 0;
    verdict_case("eq. 4, n=20, noise 0.1 px", trials, v, {});
    v.n = 6;
    verdict_case("eq. 4, n=6 (every correspondence tried)", trials, v, {});
    for (int n : {10, 50, 200, 1000}) unrelated_case(n, trials);
  }
  if (section == "families") {
    std::printf("== star-field families from scratch: any rotation, scale 0.3..3, noise 0.1 px, %s (goal >= 97%% success)\n",
                g_paper_cost ? "paper cost" : "trim from the data");
    struct Family {
      const char* label;
      int n;
      double aniso, proj, unmatched;
    };
    const Family families[] = {{"n=100 similarity", 100, 1, 0, 0},
                               {"n=100 anisotropy up to 2", 100, 2, 0, 0},
                               {"n=100 anisotropy 2, projective 0.1", 100, 2, 0.1, 0},
                               {"n=100 similarity, 20% unmatched each side", 100, 1, 0, 0.2},
                               {"n=100 anisotropy 2, projective 0.1, 50% unmatched", 100, 2, 0.1, 0.5},
                               {"n=50 similarity, 20% unmatched", 50, 1, 0, 0.2},
                               {"n=1000 anisotropy 2, 20% unmatched", 1000, 2, 0, 0.2},
                               {"n=5000 similarity, 20% unmatched", 5000, 1, 0, 0.2},
                               {"n=6 similarity", 6, 1, 0, 0},
                               {"n=6 anisotropy 2, projective 0.1", 6, 2, 0.1, 0},
                               {"n=5 similarity", 5, 1, 0, 0},
                               {"n=5 anisotropy 2, projective 0.1", 5, 2, 0.1, 0},
                               {"n=4 similarity (never determined)", 4, 1, 0, 0}};
    int k = 0;
    for (const Family& f : families)
      if (++k == family || family == 0) family_case(f.label, f.n, f.aniso, f.proj, f.unmatched, trials);
    if (family == 0 || family == k + 1)
      for (int n : {10, 100, 1000, 5000}) unrelated_case(n, n >= 5000 ? std::max(1, trials / 4) : trials);
  }
  if (all || section == "few") few_section(trials);
  if (section == "unrelated") {  // false accepts (issue 15: <= 0.1% for 10..5000 points): --trials at n <= 100,
                                 // a quarter of them at 1000, a twentieth at 5000
    std::printf("== unrelated clusters from scratch: false accepts of the verdict (goal <= 0.1%%)\n");
    if (only_n > 0) unrelated_case(only_n, trials, first);
    else
      for (int n : {5, 6, 10, 100, 1000, 5000}) unrelated_case(n, std::max(1, n <= 100 ? trials : n <= 1000 ? trials / 4 : trials / 20));
  }
  if (all || section == "scale") {
    std::printf("== time against n (default optimizer, physical, paper start, noise 0.1 px; and from scratch)\n");
    for (long n : {100L, 1000L, 10000L, 100000L}) {
      if (n > max_n) break;
      ClusterSynthOptions sn = paper;
      sn.n = static_cast<int>(n);
      sn.noise = 0.1;
      int tr = n <= 1000 ? 10 : (n <= 10000 ? 3 : 1);
      char label[80];
      o.optimizer = OptimizerKind::Default;
      o.param = Parameterization::Physical;
      std::snprintf(label, sizeof label, "n=%ld default physical with init", n);
      run_case(label, tr, sn, o, {}, true);
      o.param = Parameterization::Math;
      std::snprintf(label, sizeof label, "n=%ld from scratch", n);
      run_case(label, tr, sn, o, {}, false);
      // One cost evaluation.
      ClusterPair cp = synth_cluster_pair(physical_homography(paper_physical_params()), sn);
      ClusterCost cost(cp.A, cp.B);
      auto t0 = std::chrono::steady_clock::now();
      int reps = n <= 1000 ? 200 : 5;
      double sink = 0;
      for (int k = 0; k < reps; ++k) sink += cost(cp.truth);
      double ms = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / reps;
      std::printf("n=%-6ld one cost evaluation (eq. 3, KD-trees): %.3f ms (cost at truth %.3f px)\n", n, ms, sink / reps);
    }
  }
  return 0;
}
