// tp-sample: a deterministic subset of the records of a tpkit table file, the rest held out.
#include <array>
#include <memory>
#include <optional>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/table_sample.hpp"
#include "tpkit/core/tool_support.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::string input = "-", output = "-", rest, kind;
  long n = -1;
  uint64_t seed = 1;
  bool spread = false;
  std::vector<double> box;
  int view = 1;
};

tpkit::ReadOptions options_for(const std::string& kind) {
  if (kind == "tracks") return tpkit::tracks_read_options();
  if (kind == "matches") return tpkit::matches_read_options();
  if (kind == "points") return tpkit::points_read_options();
  if (kind.empty()) {
    tpkit::ReadOptions o;  // any kind, header required: read by its kind's options (tracks version 2, say)
    o.of_kind = [](const std::string& k) { return k == "tracks" || k == "matches" || k == "points" ? options_for(k) : tpkit::ReadOptions(); };
    return o;
  }
  throw tpkit::UsageError("--kind must be tracks, matches or points");
}
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-sample", argc, argv,
      [](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("input", o->input, "table file (tracks, matches, points) or - for stdin");
        app.add_option("-n,--count", o->n, "records to draw (default: all)")->check(tpkit::NonNegative);
        app.add_option("--seed", o->seed, "random seed");
        app.add_flag("--spread", o->spread, "draw spread evenly over the image");
        app.add_option("--box", o->box, "keep records inside X0 Y0 X1 Y1 (pixels of --view)")->expected(4);
        app.add_option("--view", o->view, "view whose position --box and --spread use")->check(tpkit::Positive);
        app.add_option("--rest", o->rest, "write the records not drawn here (held-out check set)");
        app.add_option("--kind", o->kind, "kind of headerless input: tracks, matches or points");
        app.add_option("-o,--output", o->output, "output file (default: stdout)");
        return [o]() {
          tpkit::check_outputs({{"-o", o->output}, {"--rest", o->rest}}, {o->input});
          auto opt = options_for(o->kind);
          auto t = tpkit::read_table_file(o->input, opt);
          // the records must be those of the kind the header names (a tracks file under a matches header,
          // say, is refused as every other tool refuses it)
          const std::string kind = t.kind.empty() ? o->kind : t.kind;
          if (kind == "matches") tpkit::matches_from_table(t);
          else if (kind == "tracks") tpkit::tracks_from_table(t);
          else if (kind == "points") tpkit::points_from_table(t);
          if (t.kind.empty()) t.kind = o->kind;
          tpkit::SampleOptions so;
          so.n = o->n;
          so.seed = o->seed;
          so.spread = o->spread;
          so.box_view = o->view;
          if (!o->box.empty()) so.box = std::array<double, 4>{o->box[0], o->box[1], o->box[2], o->box[3]};
          auto res = tpkit::sample_records(t, so);
          std::string how = "seed " + std::to_string(o->seed) + (o->spread ? ", spread" : "");
          if (so.box)
            how += ", box " + tpkit::format_number(o->box[0]) + " " + tpkit::format_number(o->box[1]) + " " +
                   tpkit::format_number(o->box[2]) + " " + tpkit::format_number(o->box[3]) + " in view " +
                   std::to_string(o->view);
          // write the held-out set first to a file, then the drawn set (often stdout)
          std::unique_ptr<tpkit::AtomicOutput> rest;
          if (!o->rest.empty()) {
            rest = std::make_unique<tpkit::AtomicOutput>(o->rest);
            tpkit::write_table_subset(rest->stream(), t, res.rest,
                                      {{"sample", "held out: " + std::to_string(res.rest.size()) + " of " +
                                                      std::to_string(t.rows.size()) + " records (" + how + ")"}});
          }
          tpkit::AtomicOutput out(o->output);
          tpkit::write_table_subset(out.stream(), t, res.drawn,
                                    {{"sample", "drawn: " + std::to_string(res.drawn.size()) + " of " +
                                                    std::to_string(t.rows.size()) + " records (" + how + ")"}});
          if (rest) rest->commit();
          out.commit();
          return 0;
        };
      },
      tpkit_man_page);
}
