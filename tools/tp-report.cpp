// tp-report: one self-contained HTML page (inline SVG, no network, no script) from the files of a run.
#include <memory>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/report/run_report.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::vector<std::string> inputs;
  std::string output, title = "tpkit run";
  bool no_coverage = false;
  std::vector<std::string> orthos_before, orthos_after;
};
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-report", argc, argv,
      [](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("RUN", o->inputs, "files of a run, or folders holding them")->required();
        app.add_option("-o,--output", o->output, "the HTML page")->required();
        app.add_option("--title", o->title, "the page's title");
        app.add_flag("--no-coverage", o->no_coverage, "no coverage figures (the images are not read)");
        app.add_option("--orthos-before", o->orthos_before, "orthos of the delivered models: GeoTIFFs of one grid, or a folder of *.ortho.tif (repeatable)")
            ->allow_extra_args(false);
        app.add_option("--orthos-after", o->orthos_after, "orthos of the adjusted models: GeoTIFFs of one grid, or a folder of *.ortho.tif (repeatable)")
            ->allow_extra_args(false);
        return [o]() {
          const auto files = tpkit::report_inputs(o->inputs);
          tpkit::ReportOptions ro;
          ro.orthos_before = tpkit::ortho_inputs(o->orthos_before, "--orthos-before");
          ro.orthos_after = tpkit::ortho_inputs(o->orthos_after, "--orthos-after");
          std::vector<std::string> inputs = files;
          inputs.insert(inputs.end(), ro.orthos_before.begin(), ro.orthos_before.end());
          inputs.insert(inputs.end(), ro.orthos_after.begin(), ro.orthos_after.end());
          tpkit::check_outputs({{"-o", o->output}}, inputs);
          ro.title = o->title;
          ro.coverage = !o->no_coverage;
          const std::string html = tpkit::run_report_html(files, ro);
          tpkit::write_file_atomic(o->output, html);
          std::string orthos;
          if (!ro.orthos_before.empty() || !ro.orthos_after.empty())
            orthos = ", " + std::to_string(ro.orthos_before.size()) + " orthos before and " + std::to_string(ro.orthos_after.size()) + " after";
          tpkit::summary(o->output + ": " + std::to_string(files.size()) + " files" + orthos + ", " + std::to_string(html.size() / 1024) + " KiB");
          return 0;
        };
      },
      tpkit_man_page);
}
