// tp-chain: pairwise matches files joined by (image, keypoint id) into multi-view tracks.
#include <cstdlib>
#include <iostream>
#include <memory>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/match/tracks_chain.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::vector<std::string> files, images;
  std::string out = "-";
  int min_views = 0;  // 0: not given (the option takes 2 or more); default 3, or 2 with two images
  double same = 0.01;
  bool quiet = false;
};
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-chain", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("MATCHES", o->files, "matches files")->required();
        app.add_option("--images", o->images, "images of the output, in column order (first = reference)");
        app.add_option("--min-views", o->min_views, "fewest views of a track (default: 3, or 2 with two images)")
            ->check(CLI::Validator(
                [](std::string& v) -> std::string {
                  char* end = nullptr;
                  const long n = std::strtol(v.c_str(), &end, 10);
                  if (v.empty() || *end != '\0') return "not a whole number: '" + v + "'";
                  return n < 2 ? "must be at least 2, got '" + v + "'" : std::string();
                },
                "INT >= 2"));
        app.add_option("--same-position", o->same, "keypoints of one image closer than this are one point, pixels")
            ->check(tpkit::NonNegative);
        app.add_option("-o,--output", o->out, "output tracks file (- = stdout)");
        app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
        return [o]() {
          tpkit::check_outputs({{"-o", o->out}}, o->files);
          std::vector<tpkit::Matches> ms;
          for (const auto& f : o->files) ms.push_back(tpkit::read_matches(f));
          tpkit::ChainOptions co;
          for (size_t i = 0; i < o->images.size(); ++i)
            for (size_t j = 0; j < i; ++j)
              if (o->images[i] == o->images[j])
                throw tpkit::UsageError("--images names " + o->images[i] + " twice (columns " + std::to_string(j + 1) +
                                        " and " + std::to_string(i + 1) + ")");
          co.images = o->images;
          co.same_position = o->same;
          if (o->min_views == 0) {
            size_t k = o->images.size();
            if (k == 0) {
              std::vector<std::string> seen;
              for (const auto& m : ms)
                for (const auto* r : {&m.image1, &m.image2})
                  if (std::find(seen.begin(), seen.end(), r->path) == seen.end()) seen.push_back(r->path);
              k = seen.size();
            }
            co.min_views = k == 2 ? 2 : 3;
          } else {
            co.min_views = o->min_views;
          }
          tpkit::ChainStats st;
          tpkit::Tracks t = tpkit::chain_tracks(ms, co, &st);
          tpkit::save_tracks(o->out, t);
          if (!o->quiet) {
            std::ostringstream line;
            line << st.components << " components; tracks by views:";
            for (const auto& kv : st.by_length) line << " " << kv.first << ":" << kv.second;
            line << "; merged duplicates " << st.merged_duplicates << ", dropped (reference conflict) "
                 << st.dropped_reference_conflicts << ", views dropped (conflict) " << st.views_dropped_conflicts << "; written "
                 << st.written << " tracks with " << t.views() << " views";
            tpkit::summary(line.str());
          }
          return 0;
        };
      },
      tpkit_man_page);
}
