#include "tpkit/interop/openmvg_matches.hpp"

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/text_table.hpp"

namespace fs = std::filesystem;

namespace tpkit {

namespace {

void write_sfm_data(const std::string& path, const PeerKeypoints& k) {
  AtomicOutput out(path);
  std::ostream& os = out.stream();
  os << "{\n    \"sfm_data_version\": \"0.3\",\n    \"root_path\": \"\",\n    \"views\": [";
  for (size_t v = 0; v < k.images.size(); ++v) {
    const PeerImage& im = k.images[v];
    os << (v ? "," : "") << "\n        {\n            \"key\": " << v
       << ",\n            \"value\": {\n                \"polymorphic_id\": 1073741824,\n                \"ptr_wrapper\": {\n"
       << "                    \"id\": " << 2147483649ull + v << ",\n                    \"data\": {\n"
       << "                        \"local_path\": \"\",\n                        \"filename\": \"" << image_file_name(im.ref.path)
       << "\",\n                        \"width\": " << im.ref.width << ",\n                        \"height\": " << im.ref.height
       << ",\n                        \"id_view\": " << v << ",\n                        \"id_intrinsic\": 4294967295,\n"
       << "                        \"id_pose\": " << v << "\n                    }\n                }\n            }\n        }";
  }
  os << "\n    ],\n    \"intrinsics\": [],\n    \"extrinsics\": [],\n    \"structure\": [],\n    \"control_points\": []\n}\n";
  out.commit();
}

struct View {
  ImageRef ref;
  std::vector<double> x, y;
  bool loaded = false;
};

// id_view -> image from sfm_data.json (the fields this module writes; any order inside a view).
std::map<long long, View> read_sfm_views(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  const std::string text = s.str();
  std::map<long long, View> views;
  const std::regex data_re(R"re("data"\s*:\s*\{([^{}]*)\})re");
  const std::regex name_re(R"re("filename"\s*:\s*"([^"]*)")re"), w_re(R"re("width"\s*:\s*(\d+))re"),
      h_re(R"re("height"\s*:\s*(\d+))re"), id_re(R"re("id_view"\s*:\s*(\d+))re");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), data_re); it != std::sregex_iterator(); ++it) {
    const std::string d = (*it)[1];
    std::smatch name, w, h, id;
    if (!std::regex_search(d, name, name_re) || !std::regex_search(d, id, id_re)) continue;
    View v;
    v.ref.path = name[1];
    if (std::regex_search(d, w, w_re)) v.ref.width = std::stol(w[1]);
    if (std::regex_search(d, h, h_re)) v.ref.height = std::stol(h[1]);
    views[std::stoll(id[1])] = v;
  }
  if (views.empty()) throw InputError(path, 0, "names no views (id_view, filename)");
  return views;
}

void load_feat(View& v, const std::string& folder) {
  if (v.loaded) return;
  const std::string path = (fs::path(folder) / (image_stem(v.ref.path) + ".feat")).string();
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open the features of view " + v.ref.path);
  std::string line;
  for (long n = 1; std::getline(in, line); ++n) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream s(line);
    std::vector<double> f;
    for (double d; s >> d;) f.push_back(d);
    if (!s.eof() || (f.size() != 2 && f.size() != 4 && f.size() != 6))
      throw InputError(path, n, "a feature is x y [scale orientation] or x y a11 a12 a21 a22");
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
  std::ifstream in(matches_path);
  if (!in) throw InputError(matches_path, 0, "cannot open");
  std::vector<Matches> out;
  std::string line;
  long n = 0;
  auto next = [&](std::vector<std::string>& f) {
    while (std::getline(in, line)) {
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
