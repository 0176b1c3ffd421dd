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
        return [o]() {
          const auto files = tpkit::report_inputs(o->inputs);
          tpkit::check_outputs({{"-o", o->output}}, files);
          tpkit::ReportOptions ro;
          ro.title = o->title;
          ro.coverage = !o->no_coverage;
          const std::string html = tpkit::run_report_html(files, ro);
          tpkit::write_file_atomic(o->output, html);
          tpkit::summary(o->output + ": " + std::to_string(files.size()) + " files, " + std::to_string(html.size() / 1024) + " KiB");
          return 0;
        };
      },
      tpkit_man_page);
}
