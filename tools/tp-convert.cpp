// tp-convert: tie points to and from the formats of other photogrammetry tools (ASP, MicMac, COLMAP,
// OpenMVG). Every format's conventions live in its library module (asp_match.hpp, micmac_homol.hpp,
// colmap_database.hpp, openmvg_matches.hpp); this file only picks them.
#include <filesystem>
#include <iostream>
#include <memory>

#include "tpkit/interop/asp_match.hpp"
#include "tpkit/core/atomic_output.hpp"
#include "tpkit/interop/colmap_database.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"
#include "tpkit/interop/micmac_homol.hpp"
#include "tpkit/interop/openmvg_matches.hpp"
#include "tpkit/interop/peer_keypoints.hpp"
#include "tpkit/core/tool_support.hpp"

extern const char* const tpkit_man_page;

namespace fs = std::filesystem;

namespace {

const std::vector<std::string> kFormats = {"asp", "asp-txt", "micmac", "micmac-dat", "colmap", "openmvg"};

struct Opts {
  std::string to, from, out;
  std::vector<std::string> inputs, images;
  double min_sigma = 0.1;
  std::string colmap_matches = "verified";
  bool quiet = false;
};

void check_format(const std::string& option, const std::string& name) {
  if (std::find(kFormats.begin(), kFormats.end(), name) != kFormats.end()) return;
  std::string list;
  for (const auto& f : kFormats) list += (list.empty() ? "" : ", ") + f;
  throw tpkit::UsageError(option + ": unknown format '" + name + "' (known: " + list + ")");
}

std::string join(const std::string& folder, const std::string& name) { return (fs::path(folder) / name).string(); }

// Outputs of several files: every name checked up front (two pairs on one file name are refused
// before anything is written), the folders made (removed again if the run fails).
void claim_all(const std::vector<std::string>& files, const std::vector<std::string>& inputs) {
  std::vector<std::pair<std::string, std::string>> outs;
  for (const auto& f : files) {
    const fs::path dir = fs::path(f).parent_path();
    if (!dir.empty()) tpkit::create_output_dir(dir.string());
    outs.push_back({"-o", f});
  }
  tpkit::check_outputs(outs, inputs);
}

long export_files(const Opts& o, const std::vector<tpkit::Matches>& ms) {
  const std::string& f = o.to;
  std::vector<std::string> names;
  for (const auto& m : ms) tpkit::check_peer_pair(m);  // every format names files or records after the images
  if (f == "asp" || f == "asp-txt") {
    for (const auto& m : ms) names.push_back(tpkit::asp_match_file_name(o.out, m.image1.path, m.image2.path, f == "asp-txt"));
    claim_all(names, o.inputs);
    for (size_t i = 0; i < ms.size(); ++i) {
      tpkit::AtomicOutput out(names[i]);
      if (f == "asp") tpkit::write_asp_match(out.stream(), ms[i], o.min_sigma);
      else tpkit::write_asp_match_text(out.stream(), ms[i], o.min_sigma);
      out.commit();
    }
    return static_cast<long>(names.size());
  }
  if (f == "micmac" || f == "micmac-dat") {
    const bool binary = f == "micmac-dat";
    for (const auto& m : ms) {
      names.push_back(tpkit::micmac_homol_file_name(o.out, m.image1.path, m.image2.path, binary));
      names.push_back(tpkit::micmac_homol_file_name(o.out, m.image2.path, m.image1.path, binary));
    }
    claim_all(names, o.inputs);
    for (size_t i = 0; i < names.size(); ++i) {
      tpkit::AtomicOutput out(names[i]);
      tpkit::write_micmac_homol(out.stream(), ms[i / 2], binary, i % 2 == 1);
      out.commit();
    }
    return static_cast<long>(names.size());
  }
  // COLMAP's -o is the folder of database.db and the importer's text form: a name of a database file
  // would become a folder of that name
  if (f == "colmap" && o.out.size() >= 3 && o.out.compare(o.out.size() - 3, 3, ".db") == 0)
    throw tpkit::UsageError("-o " + o.out + ": --to colmap writes a folder (database.db and the text form in it), not a "
                            "database file: name the folder");
  tpkit::PeerKeypoints k = tpkit::collect_peer_keypoints(ms, o.images);
  tpkit::size_images(k, o.images);
  tpkit::create_output_dir(o.out);
  if (f == "colmap") {
    names = {join(o.out, "database.db"), join(o.out, "matches.txt")};
    for (const auto& im : k.images) names.push_back(join(join(o.out, "keypoints"), tpkit::image_file_name(im.ref.path) + ".txt"));
    claim_all(names, o.inputs);
    tpkit::write_colmap_database(names[0], k);
    tpkit::write_colmap_text(o.out, k);
  } else {  // openmvg
    names = {join(o.out, "matches.f.txt"), join(o.out, "sfm_data.json")};
    for (const auto& im : k.images) names.push_back(join(o.out, tpkit::image_stem(im.ref.path) + ".feat"));
    claim_all(names, o.inputs);
    tpkit::write_openmvg(o.out, k);
  }
  return static_cast<long>(names.size());
}

std::vector<tpkit::Matches> import_files(const Opts& o) {
  const std::string& f = o.from;
  std::vector<tpkit::Matches> ms;
  for (const auto& in : o.inputs) {
    std::vector<tpkit::Matches> got;
    if (f == "asp" || f == "asp-txt") got.push_back(tpkit::read_asp_match(in, o.images));
    else if ((f == "micmac" || f == "micmac-dat") && fs::is_directory(in)) got = tpkit::read_micmac_homol_folder(in, o.images, f == "micmac-dat");
    else if (f == "micmac" || f == "micmac-dat") got.push_back(tpkit::read_micmac_homol(in));
    else if (f == "colmap") got = tpkit::read_colmap_database(in, o.colmap_matches == "verified");
    else got = tpkit::read_openmvg(in, o.images);
    for (auto& m : got) ms.push_back(std::move(m));
  }
  if (f == "asp" || f == "asp-txt" || f == "micmac" || f == "micmac-dat") tpkit::assign_position_ids(ms);
  tpkit::name_images(ms, o.images);
  return ms;
}

}  // namespace

int main(int argc, char** argv) {
  return tpkit::run_tool(
      "tp-convert", argc, argv,
      [&](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<Opts>();
        app.add_option("INPUT", o->inputs, "tpkit matches files (--to), or the other tool's files (--from)")->required();
        app.add_option("--to", o->to, "write this format from tpkit matches files");
        app.add_option("--from", o->from, "read this format into tpkit matches files");
        app.add_option("--images", o->images, "image files: sizes, names and order of the images");
        app.add_option("--min-sigma", o->min_sigma, "floor of the point sigma written to ASP, pixels")->check(tpkit::Positive);
        app.add_option("--colmap-matches", o->colmap_matches, "verified (two_view_geometries) or raw (matches)")
            ->check(CLI::IsMember({"verified", "raw"}));
        app.add_option("-o,--output", o->out, "output prefix (asp) or folder")->required();
        app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
        return [o]() {
          if (o->to.empty() == o->from.empty()) throw tpkit::UsageError("give exactly one of --to and --from");
          if (!o->to.empty()) check_format("--to", o->to);
          if (!o->from.empty()) check_format("--from", o->from);
          if (o->out == "-") throw tpkit::UsageError("-o names a folder or prefix, not stdout");
          // taken lexically: "o/new/../run" is o/run, so no folder o/new is made on the way (and left behind)
          o->out = fs::path(o->out).lexically_normal().string();
          long files = 0, records = 0;
          if (!o->to.empty()) {
            std::vector<tpkit::Matches> ms;
            for (const auto& in : o->inputs) ms.push_back(tpkit::read_matches(in));
            for (const auto& m : ms) records += static_cast<long>(m.size());
            files = export_files(*o, ms);
          } else {
            const std::vector<tpkit::Matches> ms = import_files(*o);
            if (ms.empty()) throw tpkit::InputError(o->inputs.front(), 0, "holds no image pair with matches");
            std::vector<std::string> names;
            for (const auto& m : ms)
              names.push_back(join(o->out, tpkit::image_stem(m.image1.path) + "__" + tpkit::image_stem(m.image2.path) + ".matches"));
            tpkit::create_output_dir(o->out);
            claim_all(names, o->inputs);
            for (size_t i = 0; i < ms.size(); ++i) {
              tpkit::save_matches(names[i], ms[i]);
              records += static_cast<long>(ms[i].size());
            }
            files = static_cast<long>(names.size());
          }
          if (!o->quiet)
            tpkit::summary((o->to.empty() ? o->from + " -> tpkit" : "tpkit -> " + o->to) + ": " + std::to_string(records) +
                           " matches, " + std::to_string(files) + " files written under " + o->out);
          return 0;
        };
      },
      tpkit_man_page);
}
