// cluster-homog: the homography between two point clusters with no known correspondences
// (Navy et al. 2005), see man/cluster-homog.1. Options -> library (cluster_*.hpp) -> files.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "tpkit/cluster/cluster_cost.hpp"
#include "tpkit/cluster/cluster_init.hpp"
#include "tpkit/cluster/cluster_optimize.hpp"
#include "tpkit/cluster/cluster_scan.hpp"
#include "tpkit/cluster/cluster_solve.hpp"
#include "tpkit/cluster/cluster_verdict.hpp"
#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/tool_support.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::string a, b, out = "-", init, pairs, scan, plot, param = "physical", optimizer = "default", model = "auto";
  uint64_t seed = 1;
  double trim = 0, truncate = 0, target = 0.25;
  long max_iterations = 10000;
  bool free_intrinsics = false, reflection = false;
  std::vector<double> range;
  int steps = 101;
  bool keep_rejected = false;
};

std::string num(double v) { return tpkit::format_number(v); }

// The field of cluster B for the verdict: its image (w x h pixels, from the points file's image line) when
// every point lies in it; else 0 (the hull of B).
double cluster_field_area(const tpkit::Points& B) {
  if (B.images.empty() || B.images.front().width <= 0 || B.images.front().height <= 0) return 0;
  const double w = static_cast<double>(B.images.front().width), h = static_cast<double>(B.images.front().height);
  for (Eigen::Index i = 0; i < B.xy.rows(); ++i)
    if (!(B.xy(i, 0) >= -0.5 && B.xy(i, 0) <= w - 0.5 && B.xy(i, 1) >= -0.5 && B.xy(i, 1) <= h - 0.5)) return 0;
  return w * h;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace tpkit;
  return run_tool("cluster-homog", argc, argv, [&](CLI::App& app) -> std::function<int()> {
    auto o = std::make_shared<Opts>();
    app.add_option("A", o->a, "cluster of image 1 (points file)")->required();
    app.add_option("B", o->b, "cluster of image 2 (points file)")->required();
    app.add_option("-o,--output", o->out, "homography file (or scan table with --scan); - for stdout");
    app.add_option("--param", o->param, "math | physical")->check(CLI::IsMember({"math", "physical"}));
    app.add_option("--init", o->init, "key = value file of starting values");
    app.add_option("--optimizer", o->optimizer, "default | random | none")
        ->check(CLI::IsMember({"default", "random", "none"}));
    app.add_option("--model", o->model, "auto | similarity | affine | homography (auto: the simplest the verdict accepts)")
        ->check(CLI::IsMember({"auto", "similarity", "affine", "homography"}));
    app.add_option("--seed", o->seed, "seed of every random choice");
    CLI::Option* trim_opt = app.add_option("--trim", o->trim, "fraction of the largest distances left out in each direction (default: from the data)");
    CLI::Option* truncate_opt = app.add_option("--truncate", o->truncate, "distances capped at this many pixels");
    app.add_option("--target", o->target, "cost in pixels at which the search stops");
    app.add_option("--max-iterations", o->max_iterations, "iteration limit");
    app.add_flag("--free-intrinsics", o->free_intrinsics, "20 free physical parameters instead of 12");
    app.add_flag("--allow-reflection", o->reflection, "the search also tries mirror-image maps");
    app.add_option("--pairs", o->pairs, "write the mutual nearest-neighbour pairs under the final h");
    app.add_option("--scan", o->scan, "parameter to scan");
    app.add_option("--range", o->range, "LO HI of the scan")->expected(2);
    app.add_option("--steps", o->steps, "values of the scan");
    app.add_option("--plot", o->plot, "SVG figure of the scan, or of the clusters before and after");
    app.add_flag("--keep-rejected", o->keep_rejected, "write the outputs of a rejected answer too (marked; exit 3)");
    return [o, trim_opt, truncate_opt]() {
      check_outputs({{"-o", o->out}, {"--pairs", o->pairs}, {"--plot", o->plot}}, {o->a, o->b, o->init});
      if (!o->scan.empty() && o->range.size() != 2) throw UsageError("--scan needs --range LO HI");
      if (o->scan.empty() && !o->range.empty()) throw UsageError("--range goes with --scan");
      if (!o->scan.empty()) check_scan(o->scan, o->range[0], o->range[1], o->steps);
      if (!(o->trim >= 0 && o->trim < 1)) throw UsageError("--trim must be in [0, 1)");
      if (!(o->truncate >= 0)) throw UsageError("--truncate must be >= 0");
      if (!(o->target >= 0)) throw UsageError("--target must be >= 0");
      if (o->max_iterations < 0) throw UsageError("--max-iterations must be >= 0");
      // the models other than the homography are the default optimizer's (cluster_solve.hpp); a scan and
      // the paper's optimizers work on the homography
      const bool homography_only = !o->scan.empty() || o->optimizer != "default";
      if (homography_only && o->model != "auto" && o->model != "homography")
        throw UsageError("--model " + o->model + " needs the default optimizer and no --scan");
      const bool automatic = o->model == "auto" && !homography_only;
      const ClusterModel model = o->model == "similarity" ? ClusterModel::Similarity
                                 : o->model == "affine"   ? ClusterModel::Affine
                                                          : ClusterModel::Homography;
      const ClusterModel least = automatic ? ClusterModel::Similarity : model;  // fewest points needed
      Points A = read_points(o->a), B = read_points(o->b);
      validate_cluster(A.xy, o->a, least);
      validate_cluster(B.xy, o->b, least);
      OptimizeStart start;
      if (!o->init.empty()) {
        ClusterInit ci = read_cluster_init_file(o->init);
        start.has_physical = ci.has_physical, start.physical = ci.physical;
        start.has_H = ci.has_H, start.H = ci.H;
      }
      OptimizeOptions oo;
      oo.param = o->param == "math" ? Parameterization::Math : Parameterization::Physical;
      oo.optimizer = o->optimizer == "random" ? OptimizerKind::Random
                     : o->optimizer == "none" ? OptimizerKind::None
                                              : OptimizerKind::Default;
      oo.free_intrinsics = o->free_intrinsics;
      oo.target = o->target;
      oo.max_iterations = o->max_iterations;
      oo.seed = o->seed;
      oo.allow_reflection = o->reflection;
      // unknown overlap by default: each direction's trim is chosen by the data (cluster_cost.hpp) unless
      // --trim or --truncate sets the robust cost by hand
      const bool from_data = trim_opt->count() == 0 && truncate_opt->count() == 0;
      CostOptions co{o->trim, o->truncate, from_data};
      ClusterCost cost(A.xy, B.xy, co);
      const double domain_b = cluster_field_area(B);
      OptimizeResult r;
      ClusterSolution sol;
      if (homography_only) {
        r = optimize_clusters(cost, start, oo);
      } else {
        SolveOptions so;
        so.optimize = oo;
        so.automatic = automatic;
        so.model = model;
        so.domain_area_b = domain_b;
        const auto t0 = std::chrono::steady_clock::now();
        sol = solve_clusters(cost, start, so);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (sol.has_homography_search) r = sol.search;
        r.H = sol.chosen.H;
        r.cost = sol.cost;
        r.evaluations = sol.hypotheses;
        r.reached_target = r.cost <= o->target;
        r.seconds = seconds;  // every model's search
        if (!sol.has_homography_search) r.start_cost = std::nan("");
        r.method = std::string(cluster_model_name(sol.chosen.model)) + ": " + sol.chosen.method;
        // physical parameters describe the homography search's answer only
        if (!(sol.has_homography_search && sol.chosen.model == ClusterModel::Homography)) r.has_physical = false;
      }

      Homography h;
      if (!A.images.empty()) h.images.push_back(A.images.front());
      if (!B.images.empty()) {
        if (h.images.empty()) h.images.push_back(ImageRef{});
        h.images.push_back(B.images.front());
      }
      h.H = r.H;
      Meta& m = h.meta;
      m.emplace_back("method", "cluster-homog (Navy et al. 2005, eq. 3 cost)");
      m.emplace_back("cluster1", o->a + " (" + std::to_string(A.size()) + " points)");
      m.emplace_back("cluster2", o->b + " (" + std::to_string(B.size()) + " points)");
      if (!homography_only) {
        std::string odds;
        for (const ModelCandidate& c : sol.candidates)
          odds += std::string(odds.empty() ? "" : ", ") + cluster_model_name(c.model) + " " +
                  (std::isfinite(c.verdict.log10_odds) ? num(std::round(c.verdict.log10_odds * 100) / 100) : "-inf");
        m.emplace_back("model", std::string(cluster_model_name(sol.chosen.model)) +
                                    (automatic ? " (auto: the fewest parameters the verdict accepts that match as well as the richer; "
                                               : " (") +
                                    "log10 odds " + odds + ")");
      } else {
        m.emplace_back("model", "homography");
      }
      m.emplace_back("parameterization", o->param + (o->free_intrinsics ? " (20 free)" : ""));
      m.emplace_back("optimizer", o->optimizer + " (" + r.method + ")");
      m.emplace_back("seed", std::to_string(o->seed));
      if (from_data) {
        const auto kept = cost.kept_fractions(r.H);
        m.emplace_back("trim", "from the data (" + num(std::round((1 - kept.first) * 1e3) / 1e3) + " of cluster1, " +
                                   num(std::round((1 - kept.second) * 1e3) / 1e3) + " of cluster2 left out)");
      } else {
        m.emplace_back("trim", num(o->trim));
      }
      m.emplace_back("truncate", num(o->truncate));
      m.emplace_back("cost_start", std::isfinite(r.start_cost) ? num(r.start_cost) : "none (no start)");
      m.emplace_back("cost", num(r.cost));
      m.emplace_back("target", num(o->target));
      m.emplace_back("reached_target", r.reached_target ? "yes" : "no");
      m.emplace_back("iterations", std::to_string(r.iterations));
      m.emplace_back("evaluations", std::to_string(r.evaluations));
      m.emplace_back("local_rounds", std::to_string(r.local_rounds));
      m.emplace_back("time_s", num(r.seconds));
      if (r.has_physical) {
        auto a = r.physical.array();
        for (int i = 0; i < kPhysicalParamCount; ++i) m.emplace_back(physical_param_names()[i], num(a[i]));
      }
      std::ostringstream msg;
      msg << "cost " << r.cost << " px (start " << r.start_cost << "), " << r.iterations << " iterations, "
          << r.seconds * 1e3 << " ms, " << r.method;
      std::fprintf(stderr, "cluster-homog: %s\n", msg.str().c_str());
      if (!r.reached_target) warn("the cost did not reach the target of " + num(o->target) + " px");

      // the verdict (not for a scan, which is a diagnostic of the cost): accepted only when far more
      // points match than chance gives (cluster_verdict.hpp); never depends on --trim or --truncate
      Verdict verdict;
      if (o->scan.empty()) {
        if (homography_only) {
          VerdictOptions vo;
          vo.hypotheses = std::max(1L, r.evaluations);
          vo.domain_area_b = domain_b;
          verdict = judge_homography(cost, r.H, vo);
        } else {
          verdict = sol.chosen.verdict;
        }
        m.emplace_back("verdict", verdict.accepted ? "accepted" : "rejected");
        if (!verdict.degenerate.empty()) m.emplace_back("degenerate", verdict.degenerate);
        if (!verdict.undetermined.empty()) m.emplace_back("undetermined", verdict.undetermined);
        m.emplace_back("verdict_log10_odds", std::isfinite(verdict.log10_odds) ? num(std::round(verdict.log10_odds * 100) / 100) : "-inf");
        m.emplace_back("inliers", std::to_string(verdict.inliers) + " of " + std::to_string(verdict.candidates) +
                                      " points of cluster1 (" + std::to_string(verdict.mapped_into_b) +
                                      " mapped into cluster2), mutual nearest neighbours within " +
                                      num(std::round(verdict.radius_px * 1e4) / 1e4) + " px (chance: " +
                                      num(std::round(verdict.expected * 100) / 100) + ")");
        const std::string why =
            !verdict.degenerate.empty()     ? "degenerate: " + verdict.degenerate
            : !verdict.undetermined.empty() ? "h is not determined: " + verdict.undetermined
                                            : std::to_string(verdict.inliers) + " of " + std::to_string(verdict.candidates) +
                                                  " points matched within " + num(std::round(verdict.radius_px * 1e3) / 1e3) +
                                                  " px, chance " + num(std::round(verdict.expected * 10) / 10) + "; log10 odds " +
                                                  num(std::round(verdict.log10_odds * 10) / 10);
        std::fprintf(stderr, "cluster-homog: verdict: %s (%s)\n", verdict.accepted ? "accepted" : "rejected", why.c_str());
        if (!verdict.accepted && !o->keep_rejected) return kExitNoAnswer;  // nothing written
      }

      if (!o->scan.empty()) {
        PhysicalParams* phys = r.has_physical ? &r.physical : nullptr;
        PhysicalParams from_init = start.physical;
        if (!phys && start.has_physical && o->optimizer == "none") phys = &from_init;
        auto rows = scan_cost(cost, o->scan, r.H, phys, o->range[0], o->range[1], o->steps);
        if (rows.empty()) throw NumericalError("every scanned value gave a singular homography");
        if (!o->plot.empty())
          plot_scan(o->plot, rows, o->scan, "cluster cost against " + o->scan + " (" + o->param + " parameters)");
        save_scan(o->out, rows, o->scan, h.images, m);
      } else {
        if (!o->plot.empty()) {
          Eigen::Matrix3d H0 = start.has_H ? start.H
                               : start.has_physical ? physical_homography(start.physical)
                                                    : Eigen::Matrix3d::Identity();
          plot_clusters(o->plot, A.xy, B.xy, H0, cost(H0), r.H, r.cost);
        }
        save_homography(o->out, h);
      }
      if (!o->pairs.empty()) save_pairs(o->pairs, cost, mutual_pairs(cost, r.H), h.images, m);
      return o->scan.empty() && !verdict.accepted ? kExitNoAnswer : 0;  // --keep-rejected: written, marked
    };
  }, tpkit_man_page);
}
