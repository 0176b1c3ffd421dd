// tp-chain: pairwise matches files joined by (image, keypoint id) into multi-view tracks.
#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <sstream>
#include <thread>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/match/tracks_chain.hpp"
#include "tpkit/match/tracks_coverage.hpp"
#include "tpkit/match/tracks_epipolar_check.hpp"
#include "tpkit/rpc/rpc_io.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::vector<std::string> files, images;
  std::string out = "-", coverage;
  int min_views = 0;  // 0: not given (the option takes 2 or more); default 3 with three images, else 2
  double same = 0.01;
  bool quiet = false;
  bool unrefined = false;
  double closure = 0.5;
  double rpc_check = 0;  // pixels; 0: no check through the models
  std::vector<std::string> rpc_files;
  int threads = 0;
};
}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-chain", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("MATCHES", o->files, "matches files");  // required: checked below, with the reason
        app.add_option("--images", o->images, "images of the output, in column order (first = reference)");
        app.add_option("--min-views", o->min_views, "fewest views of a written track (default: 3 with three images, else 2)")
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
        app.add_option("--closure", o->closure, "redundant links must agree within this (or 5 sigma of the cycle), pixels; 0 = no check")
            ->check(tpkit::NonNegative);
        app.add_option("--rpc-check", o->rpc_check,
                       "drop views the others contradict through the RPC models: least tolerance across the epipolar curves "
                       "after each pair's bias, pixels (0 = no check)")
            ->check(tpkit::NonNegative);
        app.add_option("--rpc", o->rpc_files, "IMG=FILE: the RPC model of IMG for --rpc-check (txt, RPB, DIMAP XML or TIFF tag)");
        app.add_option("--threads", o->threads, "worker threads of --rpc-check (0 = all cores)")->check(CLI::Range(0, tpkit::kMaxThreads));
        app.add_flag("--unrefined", o->unrefined, "chain matches whose LSM refinement was rejected (refined 0) too");
        app.add_option("-o,--output", o->out, "output tracks file (- = stdout)");
        app.add_option("--coverage", o->coverage, "SVG figure: tie points per cell over each image's thumbnail");
        app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
        return [o]() {
          // --images takes every name up to the next option, the matches files after it too
          if (o->files.empty())
            throw tpkit::UsageError(o->images.empty() ? "no MATCHES files given"
                                                      : "no MATCHES files given: --images took every name after it (the last " +
                                                            o->images.back() + "): put the matches files first, or end the images with --");
          tpkit::check_outputs({{"-o", o->out}, {"--coverage", o->coverage}}, o->files);
          for (size_t i = 0; i < o->images.size(); ++i)
            for (size_t j = 0; j < i; ++j)
              if (o->images[i] == o->images[j])
                throw tpkit::UsageError("--images names " + o->images[i] + " twice (columns " + std::to_string(j + 1) +
                                        " and " + std::to_string(i + 1) + ")");
          // the default --min-views depends on the number of images: the files are read first (one at a
          // time, each dropped once its links are taken), the option applied at the join
          tpkit::ChainOptions co;
          co.images = o->images;
          co.same_position = o->same;
          co.unrefined = o->unrefined;
          co.closure = o->closure;
          co.min_views = 2;
          tpkit::TrackChainer chainer(co);
          std::vector<std::string> seen;
          for (const auto& f : o->files) {
            const tpkit::Matches m = tpkit::read_matches(f);
            for (const auto* r : {&m.image1, &m.image2})
              if (std::find(seen.begin(), seen.end(), r->path) == seen.end()) seen.push_back(r->path);
            chainer.add(m);
          }
          const size_t k = o->images.empty() ? seen.size() : o->images.size();
          co.min_views = o->min_views != 0 ? o->min_views : k == 3 ? 3 : 2;
          chainer.set_min_views(co.min_views);
          if (!o->rpc_files.empty() && o->rpc_check == 0) throw tpkit::UsageError("--rpc goes with --rpc-check");
          const tpkit::ChainStats& st = chainer.join();
          tpkit::AtomicOutput out(o->out);
          tpkit::EpipolarCheckStats ec;
          if (o->rpc_check > 0) {
            // the tracks in memory, checked through the models, then written
            tpkit::Tracks T = tpkit::chained_tracks(chainer, st);
            std::vector<std::string> paths;
            for (const auto& im : T.images) paths.push_back(im.path);
            const auto overrides = tpkit::resolve_rpc_overrides(tpkit::parse_rpc_overrides(o->rpc_files), paths);
            std::vector<tpkit::RpcModel> models;
            models.reserve(paths.size());
            for (const auto& p : paths) models.push_back(tpkit::load_image_rpc(p, overrides).model);
            std::vector<const tpkit::RpcModel*> ptr;
            for (const auto& m : models) ptr.push_back(&m);
            tpkit::EpipolarCheckOptions eo;
            eo.threshold = o->rpc_check;
            eo.min_views = co.min_views;
            eo.threads = o->threads > 0 ? o->threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
            eo.threads = std::min(eo.threads, tpkit::kMaxThreads);
            ec = tpkit::epipolar_check(T, ptr, eo);
            tpkit::note_epipolar_check(T, ec, o->rpc_check);
            tpkit::write_tracks(out.stream(), T);
            if (!o->coverage.empty()) tpkit::save_tracks_coverage(o->coverage, chainer);
          } else {
            chainer.write(out.stream());
            if (!o->coverage.empty()) tpkit::save_tracks_coverage(o->coverage, chainer);
          }
          out.commit();
          if (!o->quiet) {
            std::ostringstream line;
            line << st.components << " components; tracks by views:";
            for (const auto& kv : st.by_length) line << " " << kv.first << ":" << kv.second;
            line << "; merged duplicates " << st.merged_duplicates << ", dropped (reference conflict) "
                 << st.dropped_reference_conflicts << ", views dropped (conflict) " << st.views_dropped_conflicts << ", views dropped (closure) "
                 << st.views_dropped_closure << ", links left out (closure) " << st.links_dropped_closure << "; written "
                 << st.written << " tracks of " << co.min_views << " views or more among " << k << " images";
            if (st.written > 0) {
              line << " (by views:";
              for (const auto& kv : st.written_by_length) line << " " << kv.first << ":" << kv.second;
              line << ")";
            }
            if (o->rpc_check > 0)
              line << "; --rpc-check: " << ec.pairs_judged << " image pairs judged (median sigma " << ec.median_sigma
                   << " px, bias up to " << ec.largest_bias << " px), " << ec.views_dropped << " views dropped, "
                   << ec.tracks_removed << " tracks removed";
            if (st.unrefined_left_out > 0) line << "; unrefined matches left out " << st.unrefined_left_out << " (--unrefined chains them)";
            tpkit::summary(line.str());
          }
          return 0;
        };
      },
      tpkit_man_page);
}
