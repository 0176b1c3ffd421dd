// tp-merge: the matches files of one pair (the regions of a tiled tp-match run) combined into one,
// duplicates removed.
#include <iostream>
#include <memory>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/match/matches_merge.hpp"
#include "tpkit/core/tool_support.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::vector<std::string> files;
  std::string out = "-";
  bool quiet = false;
  tpkit::MergeOptions merge;
};
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-merge", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("MATCHES", o->files, "matches files of one pair")->required();
        app.add_option("-o,--output", o->out, "output matches file (- = stdout)");
        app.add_option("--same-position", o->merge.same_position,
                       "records of one match closer than this are one, pixels; farther apart, a conflict")
            ->check(tpkit::NonNegative);
        app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
        return [o]() {
          tpkit::check_outputs({{"-o", o->out}}, o->files);
          std::vector<tpkit::Matches> ms;
          for (const auto& f : o->files) ms.push_back(tpkit::read_matches(f));
          tpkit::MergeStats st;
          const tpkit::Matches m = tpkit::merge_matches(ms, &st, o->merge);
          tpkit::save_matches(o->out, m);
          if (!o->quiet)
            tpkit::summary(std::to_string(st.files) + " files, " + std::to_string(st.records) + " records: " +
                           std::to_string(st.duplicates) + " duplicates, " + std::to_string(st.conflicts) +
                           " conflicts dropped; written " + std::to_string(st.written));
          return 0;
        };
      },
      tpkit_man_page);
}
