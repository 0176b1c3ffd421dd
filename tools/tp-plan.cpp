// tp-plan: the job list of a scaled-out tie-point run (pairs x regions, merge, chain, and the RPC
// adjustment with its ground points) for make -j, GNU parallel and Slurm job arrays.
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/plan/scale_out_plan.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tool_support.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::vector<std::string> images;
  std::string list, match_options, adjust_options, ground_options, ortho_options, refine_options, adjust_model;
  std::vector<std::string> fixed;
  tpkit::PlanOptions p;
  bool quiet = false, adjust = false, no_adjust = false, no_refine = false;
};

}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-plan", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("IMAGES", o->images, "images (or --list)");
        app.add_option("--list", o->list, "file of image paths, one a line");
        app.add_option("-o,--work", o->p.work, "work folder shared by every machine: plan, cache, outputs")->required();
        app.add_option("--tile", o->p.tile, "region size, image-1 pixels")->check(CLI::Range(256L, 1L << 30));
        app.add_option("--min-overlap", o->p.min_overlap, "pair two images when their footprints overlap by this fraction of the smaller, 0 to 1")
            ->check(CLI::Range(0.0, 1.0));
        app.add_option("--overlap", o->p.overlap, "regions grown by this on every side, pixels")->check(tpkit::NonNegative);
        app.add_option("--detect-tile", o->p.detect_tile, "tp-match --tile (detection tile, pixels) of every job; 0 = tp-match's default")
            ->check(tpkit::NonNegative);
        app.add_option("--detect-regions", o->p.detect_regions, "regions of a row per detection job (default 4)")->check(CLI::Range(1L, 1L << 20));
        app.add_option("--threads", o->p.threads, "threads of each tp-match, tp-refine, rpc-adjust and tp-ground job (Slurm --cpus-per-task)")->check(CLI::Range(1, 1024));
        app.add_option("--bin", o->p.bin, "folder of the tpkit tools on the machines (default: on PATH)");
        app.add_option("--match-options", o->match_options, "more tp-match options for every match job, space separated");
        app.add_flag("--adjust", o->adjust, "end with rpc-adjust and tp-ground; refused when an image has no RPC model");
        app.add_flag("--no-adjust", o->no_adjust, "end with the chain (tracks.tracks)");
        app.add_option("--adjust-model", o->adjust_model, "rpc-adjust --model: shift, drift or affine (default affine)");
        app.add_option("--fixed", o->fixed, "rpc-adjust --fixed: an image whose model is kept (repeatable)")
            ->allow_extra_args(false);  // one image each: `--fixed A B C` leaves B and C to IMAGES
        app.add_option("--adjust-options", o->adjust_options, "more rpc-adjust options, space separated");
        app.add_option("--ground-options", o->ground_options, "more tp-ground options, space separated");
        app.add_flag("--no-refine", o->no_refine, "no refine stage: the adjustment takes the chain's tracks as they are");
        app.add_option("--refine-options", o->refine_options, "more tp-refine options, space separated");
        app.add_option("--ortho-options", o->ortho_options, "end with the orthos through the adjusted models (tp-ortho with these options: --dem FILE or --height H, ...)");
        app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
        return [o]() {
          std::vector<std::string> paths = o->images;
          if (!o->list.empty())
            for (const auto& p : tpkit::read_image_list(o->list)) paths.push_back(p);
          std::istringstream mo(o->match_options);
          for (std::string a; mo >> a;) {
            if (o->p.detect_tile > 0 && (a == "--tile" || a.rfind("--tile=", 0) == 0))
              throw tpkit::UsageError("--match-options: the detection tile is tp-plan's --detect-tile");
            o->p.match_args.push_back(a);
          }
          // any option of the adjustment asks for it: refused, not dropped, when it cannot be made
          const bool asked = o->adjust || !o->adjust_model.empty() || !o->fixed.empty() || !o->adjust_options.empty() ||
                             !o->ground_options.empty() || !o->ortho_options.empty() || !o->refine_options.empty();
          if (o->no_adjust && asked)
            throw tpkit::UsageError("--no-adjust excludes --adjust, --adjust-model, --fixed, --adjust-options, --ground-options, --refine-options and --ortho-options");
          if (o->no_refine && !o->refine_options.empty()) throw tpkit::UsageError("--no-refine excludes --refine-options");
          o->p.refine = !o->no_refine;
          o->p.adjust = o->no_adjust ? tpkit::PlanOptions::Adjust::off : asked ? tpkit::PlanOptions::Adjust::on : tpkit::PlanOptions::Adjust::automatic;
          if (!o->adjust_model.empty()) o->p.adjust_model = o->adjust_model;
          for (const auto& f : o->fixed) o->p.fixed.push_back(std::filesystem::absolute(f).lexically_normal().string());
          o->p.adjust_args = tpkit::plan_tool_args(o->adjust_options, "rpc-adjust", "--adjust-options");
          o->p.ground_args = tpkit::plan_tool_args(o->ground_options, "tp-ground", "--ground-options");
          o->p.ortho_args = tpkit::plan_tool_args(o->ortho_options, "tp-ortho", "--ortho-options");
          o->p.refine_args = tpkit::plan_tool_args(o->refine_options, "tp-refine", "--refine-options");
          o->p.work = std::filesystem::absolute(o->p.work).lexically_normal().string();
          if (!o->p.bin.empty()) o->p.bin = std::filesystem::absolute(o->p.bin).lexically_normal().string();
          tpkit::shell_quote(o->p.work);
          const auto images = tpkit::plan_images(paths);
          const tpkit::Plan plan = tpkit::make_plan(images, o->p);
          tpkit::write_plan(plan, o->p);
          if (!o->quiet)
            tpkit::summary(std::to_string(images.size()) + " images, " + std::to_string(plan.pairs.size()) + " pairs" +
                           (plan.pairs_below_overlap ? " (" + std::to_string(plan.pairs_below_overlap) + " more whose footprints overlap by less than --min-overlap " +
                                                           tpkit::format_figure(o->p.min_overlap) + " left out)" : std::string()) + ", " +
                           std::to_string(plan.detect.size()) + " detection jobs, " + std::to_string(plan.tiles.size()) +
                           " region jobs, " + (plan.adjust.empty() ? "ending with the chain" : "ending with " + std::string(plan.refine.empty() ? "" : "the multi-image refinement and ") + "the adjustment (" + o->p.adjust_model + ")") +
                           " in " + tpkit::plan_result(plan) + (plan.ortho.empty() ? std::string() : " and the orthos in orthos/") + "; make -C " + tpkit::shell_quote(o->p.work) + " -f plan.mk -j N, or bash " +
                           tpkit::shell_quote(o->p.work + "/run-parallel.sh") + " -j N, or bash " +
                           tpkit::shell_quote(o->p.work + "/submit-slurm.sh"));
          return 0;
        };
      },
      tpkit_man_page);
}
