#include "tpkit/interop/openmvg_matches.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/text_table.hpp"

namespace fs = std::filesystem;

namespace tpkit {

namespace {

// cereal's JSON form of the views (see the header), keys in cereal's order; names escaped by the JSON
// writer (a quote or a backslash in a file name stays a valid file).
void write_sfm_data(const std::string& path, const PeerKeypoints& k) {
  nlohmann::ordered_json doc;
  doc["sfm_data_version"] = "0.3";
  doc["root_path"] = "";
  doc["views"] = nlohmann::ordered_json::array();
  for (size_t v = 0; v < k.images.size(); ++v) {
    const PeerImage& im = k.images[v];
    nlohmann::ordered_json data;
    data["local_path"] = "";
    data["filename"] = image_file_name(im.ref.path);
    data["width"] = im.ref.width;
    data["height"] = im.ref.height;
    data["id_view"] = v;
    data["id_intrinsic"] = 4294967295ull;
    data["id_pose"] = v;
    nlohmann::ordered_json ptr;
    ptr["id"] = 2147483649ull + v;
    ptr["data"] = std::move(data);
    nlohmann::ordered_json value;
    value["polymorphic_id"] = 1073741824;
    value["ptr_wrapper"] = std::move(ptr);
    nlohmann::ordered_json view;
    view["key"] = v;
    view["value"] = std::move(value);
    doc["views"].push_back(std::move(view));
  }
  for (const char* section : {"intrinsics", "extrinsics", "structure", "control_points"}) doc[section] = nlohmann::ordered_json::array();
  std::string text;
  try {
    text = doc.dump(4);
  } catch (const nlohmann::json::type_error&) {  // a name that is not UTF-8
    throw InputError(path, 0, "an image file name is not valid UTF-8, which JSON requires");
  }
  AtomicOutput out(path);
  out.stream() << text << '\n';
  out.commit();
}

struct View {
  ImageRef ref;
  std::vector<double> x, y;
  bool loaded = false;
};

// id_view -> image from sfm_data.json, parsed as JSON (nlohmann::json): views[k].value.ptr_wrapper.data
// holds filename, id_view and (optional) width, height; the other fields and sections are ignored.
std::map<long long, View> read_sfm_views(const std::string& path) {
  std::ifstream in = open_input_file(path, InputKind::regular);
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, 0, std::string("not valid JSON: ") + e.what());
  }
  if (!doc.is_object() || !doc.contains("views") || !doc["views"].is_array())
    throw InputError(path, 0, "not an OpenMVG sfm_data file: no \"views\" array");
  std::map<long long, View> views;
  const nlohmann::json& list = doc["views"];
  for (size_t k = 0; k < list.size(); ++k) {
    const std::string where = "views[" + std::to_string(k) + "]";
    const nlohmann::json* d = &list[k];
    for (const char* key : {"value", "ptr_wrapper", "data"}) {
      if (!d->is_object() || !d->contains(key)) throw InputError(path, 0, where + ": no value.ptr_wrapper.data object");
      d = &(*d)[key];
    }
    if (!d->is_object()) throw InputError(path, 0, where + ": no value.ptr_wrapper.data object");
    auto whole = [&](const char* key, bool required) -> long long {
      if (!d->contains(key)) {
        if (required) throw InputError(path, 0, where + ": no \"" + std::string(key) + "\"");
        return 0;
      }
      const nlohmann::json& v = (*d)[key];
      if (!v.is_number_unsigned() || v.get<unsigned long long>() > static_cast<unsigned long long>(1LL << 62))
        throw InputError(path, 0, where + ": \"" + std::string(key) + "\" is not a whole number >= 0: " + v.dump());
      return v.get<long long>();
    };
    if (!d->contains("filename") || !(*d)["filename"].is_string()) throw InputError(path, 0, where + ": no \"filename\" string");
    View v;
    v.ref.path = (*d)["filename"].get<std::string>();
    v.ref.width = whole("width", false);
    v.ref.height = whole("height", false);
    const long long id = whole("id_view", true);
    const auto [it, fresh] = views.emplace(id, v);
    if (!fresh)
      throw InputError(path, 0, where + ": view id " + std::to_string(id) + " is also that of " + it->second.ref.path +
                                    ": one id names one view");
  }
  if (views.empty()) throw InputError(path, 0, "names no views (id_view, filename)");
  return views;
}

void load_feat(View& v, const std::string& folder) {
  if (v.loaded) return;
  const std::string path = (fs::path(folder) / (image_stem(v.ref.path) + ".feat")).string();
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, 0, "no such file: the features of view " + v.ref.path);
  std::ifstream in = open_input_file(path, InputKind::file);
  std::string line;
  for (long n = 1; read_text_line(in, line, path, n); ++n) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream s(line);
    std::vector<double> f;
    for (double d; s >> d;) f.push_back(d);
    if (!s.eof() || (f.size() != 2 && f.size() != 4 && f.size() != 6))
      throw InputError(path, n, "a feature is x y [scale orientation] or x y a11 a12 a21 a22");
    if (!std::isfinite(f[0]) || !std::isfinite(f[1])) throw InputError(path, n, "the position is not finite");
    v.x.push_back(f[0]);
    v.y.push_back(f[1]);
  }
  v.loaded = true;
}

long long parse_int(const std::string& s, const std::string& path, long line) {
  try {
    size_t end = 0;
    const long long v = std::stoll(s, &end);
    if (end == s.size() && v >= 0) return v;
  } catch (const std::exception&) {
  }
  throw InputError(path, line, "'" + s + "' is not an index");
}

}  // namespace

void write_openmvg(const std::string& folder, const PeerKeypoints& k) {
  for (const PeerImage& im : k.images) {
    AtomicOutput out((fs::path(folder) / (image_stem(im.ref.path) + ".feat")).string());
    for (size_t e = 0; e < im.size(); ++e)
      out.stream() << format_number(static_cast<float>(im.x[e])) << ' ' << format_number(static_cast<float>(im.y[e])) << " 1 0\n";
    out.commit();
  }
  AtomicOutput m((fs::path(folder) / "matches.f.txt").string());
  for (const PeerPair& p : k.pairs) {
    const bool swap = p.image1 > p.image2;
    m.stream() << (swap ? p.image2 : p.image1) << ' ' << (swap ? p.image1 : p.image2) << '\n' << p.idx1.size() << '\n';
    for (size_t r = 0; r < p.idx1.size(); ++r)
      m.stream() << (swap ? p.idx2[r] : p.idx1[r]) << ' ' << (swap ? p.idx1[r] : p.idx2[r]) << '\n';
  }
  m.commit();
  write_sfm_data((fs::path(folder) / "sfm_data.json").string(), k);
}

std::vector<Matches> read_openmvg(const std::string& matches_path, const std::vector<std::string>& images) {
  const std::string folder = fs::path(matches_path).parent_path().string();
  const std::string sfm = (fs::path(folder.empty() ? "." : folder) / "sfm_data.json").string();
  std::map<long long, View> views;
  if (fs::exists(sfm)) {
    views = read_sfm_views(sfm);
  } else {
    if (images.empty()) throw InputError(matches_path, 0, "no sfm_data.json beside it: name the views in order with --images");
    for (size_t v = 0; v < images.size(); ++v) views[static_cast<long long>(v)].ref.path = images[v];
  }
  std::ifstream in = open_input_file(matches_path, InputKind::file);
  std::vector<Matches> out;
  std::string line;
  long n = 0;
  auto next = [&](std::vector<std::string>& f) {
    while (read_text_line(in, line, matches_path, n + 1)) {
      ++n;
      std::istringstream s(line);
      f.clear();
      for (std::string w; s >> w;) f.push_back(w);
      if (!f.empty()) return true;
    }
    return false;
  };
  std::vector<std::string> f;
  while (next(f)) {
    if (f.size() != 2) throw InputError(matches_path, n, "a pair block starts with the two view ids 'I J'");
    const long long I = parse_int(f[0], matches_path, n), J = parse_int(f[1], matches_path, n);
    auto a = views.find(I), b = views.find(J);
    if (a == views.end() || b == views.end()) throw InputError(matches_path, n, "a view id that names no image");
    if (I == J) throw InputError(matches_path, n, "pairs a view with itself");
    load_feat(a->second, folder);
    load_feat(b->second, folder);
    if (!next(f) || f.size() != 1) throw InputError(matches_path, n, "the count of matches expected after 'I J'");
    const long long count = parse_int(f[0], matches_path, n);
    Matches m = peer_matches(a->second.ref, b->second.ref, "openmvg", matches_path);
    RecordList recs;
    for (long long r = 0; r < count; ++r) {
      if (!next(f)) throw InputError(matches_path, n, "truncated: the block announces " + std::to_string(count) + " matches");
      if (f.size() != 2) throw InputError(matches_path, n, "a match is two keypoint indices 'i j'");
      const long long i = parse_int(f[0], matches_path, n), j = parse_int(f[1], matches_path, n);
      if (i >= static_cast<long long>(a->second.x.size()) || j >= static_cast<long long>(b->second.x.size()))
        throw InputError(matches_path, n, "a keypoint index beyond the .feat file of its view");
      recs.add(i, a->second.x[i], a->second.y[i], j, b->second.x[j], b->second.y[j]);
    }
    recs.store(m);
    out.push_back(std::move(m));
  }
  return out;
}

}  // namespace tpkit
