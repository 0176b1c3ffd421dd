#include "tpkit/interop/micmac_homol.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "binary_stream.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/interop/peer_keypoints.hpp"
#include "tpkit/core/text_table.hpp"

namespace fs = std::filesystem;

namespace tpkit {

namespace {

double weight_of(const Matches& m, size_t r) {
  const int c = m.extra.find("weight");
  return c < 0 ? 1.0 : m.extra.values(r, c);
}

struct HomolRecords {
  RecordList records;
  std::vector<double> weight;
  void add(double x1, double y1, double x2, double y2, double w) {
    const long long r = static_cast<long long>(records.size());
    records.add(r, x1, y1, r, x2, y2);
    weight.push_back(w);
  }
  void store(Matches& m) const {
    records.store(m);
    m.extra.names = {"weight"};
    m.extra.values = Eigen::Map<const Eigen::VectorXd>(weight.data(), static_cast<Eigen::Index>(weight.size()));
  }
};

void read_dat(HomolRecords& out, const std::string& path) {
  const std::string data = read_binary_file(path);
  ByteReader in(data, path);
  const int32_t dim = in.get<int32_t>("dim");
  if (dim != 2) throw InputError(path, 0, "dim is " + std::to_string(dim) + ", a pair file holds 2");
  const int32_t n = in.get<int32_t>("the count");
  if (n < 0) throw InputError(path, 0, "negative count " + std::to_string(n));
  if (static_cast<size_t>(n) * kMicmacRecordBytes != in.left())
    throw InputError(path, 0, "the count says " + std::to_string(n) + " records (" +
                                  std::to_string(kMicmacHeaderBytes + static_cast<size_t>(n) * kMicmacRecordBytes) +
                                  " bytes), the file has " + std::to_string(data.size()) + " bytes");
  for (int32_t i = 0; i < n; ++i) {
    const int32_t np = in.get<int32_t>("npoints");
    if (np != 2) throw InputError(path, 0, "record " + std::to_string(i) + " has " + std::to_string(np) + " points, not 2");
    const double w = in.get<double>("weight");
    const double x1 = in.get<double>("x1"), y1 = in.get<double>("y1"), x2 = in.get<double>("x2"), y2 = in.get<double>("y2");
    if (!std::isfinite(w) || !std::isfinite(x1) || !std::isfinite(y1) || !std::isfinite(x2) || !std::isfinite(y2))
      throw InputError(path, 0, "record " + std::to_string(i) + " (byte " + std::to_string(kMicmacHeaderBytes + i * kMicmacRecordBytes) +
                                    ") holds a non-finite " + (std::isfinite(w) ? "position" : "weight"));
    out.add(x1, y1, x2, y2, w);
  }
}

void read_txt(HomolRecords& out, const std::string& path) {
  std::ifstream in = open_input_file(path, InputKind::file);
  std::string line;
  for (long n = 1; read_text_line(in, line, path, n); ++n) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream s(line);
    double x1, y1, x2, y2, w = 1;
    std::string extra;
    if (!(s >> x1 >> y1 >> x2 >> y2)) throw InputError(path, n, "a MicMac match is x1 y1 x2 y2 [weight]");
    if (!(s >> w)) {
      if (!s.eof()) throw InputError(path, n, "the weight is not a number");
      w = 1;
    } else if (s >> extra) {
      throw InputError(path, n, "more than five fields");
    }
    if (!std::isfinite(x1) || !std::isfinite(y1) || !std::isfinite(x2) || !std::isfinite(y2) || !std::isfinite(w))
      throw InputError(path, n, "a field is not finite");
    out.add(x1, y1, x2, y2, w);
  }
}

}  // namespace

std::string micmac_homol_file_name(const std::string& homol, const std::string& image1, const std::string& image2, bool binary) {
  return (fs::path(homol) / ("Pastis" + image_file_name(image1)) / (image_file_name(image2) + (binary ? ".dat" : ".txt")))
      .string();
}

void write_micmac_homol(std::ostream& os, const Matches& m, bool binary, bool reversed) {
  const int a = reversed ? 2 : 0, b = reversed ? 0 : 2;
  if (binary) {
    put_le<int32_t>(os, 2);
    put_le<int32_t>(os, static_cast<int32_t>(m.size()));
  }
  for (size_t r = 0; r < m.size(); ++r) {
    const double w = weight_of(m, r);
    if (binary) {
      put_le<int32_t>(os, 2);
      put_le<double>(os, w);
      for (double v : {m.xy(r, a), m.xy(r, a + 1), m.xy(r, b), m.xy(r, b + 1)}) put_le<double>(os, v);
    } else {
      os << format_number(m.xy(r, a)) << ' ' << format_number(m.xy(r, a + 1)) << ' ' << format_number(m.xy(r, b)) << ' '
         << format_number(m.xy(r, b + 1)) << ' ' << format_number(w) << '\n';
    }
  }
}

Matches read_micmac_homol(const std::string& path) {
  const fs::path p(path);
  const std::string dir = p.parent_path().filename().string();
  if (dir.rfind("Pastis", 0) != 0 || dir.size() == 6)
    throw InputError(path, 0, "a MicMac tie point file lies in a folder Pastis<IMAGE1>");
  const std::string ext = p.extension().string();
  if (ext != ".dat" && ext != ".txt") throw InputError(path, 0, "a MicMac tie point file ends in .dat or .txt");
  Matches m = peer_matches(ImageRef{dir.substr(6), 0, 0}, ImageRef{p.stem().string(), 0, 0},
                           ext == ".dat" ? "micmac-dat" : "micmac", path);
  HomolRecords recs;
  if (ext == ".dat") read_dat(recs, path);
  else read_txt(recs, path);
  recs.store(m);
  return m;
}

std::vector<Matches> read_micmac_homol_folder(const std::string& homol, const std::vector<std::string>& order, bool binary) {
  std::error_code ec;
  if (!fs::is_directory(homol, ec)) throw InputError(homol, 0, "not a folder (a MicMac Homol folder expected)");
  std::map<std::pair<std::string, std::string>, std::string> files;  // (name1, name2) -> path
  for (const auto& d : fs::directory_iterator(homol)) {
    const std::string dn = d.path().filename().string();
    if (!d.is_directory() || dn.rfind("Pastis", 0) != 0) continue;
    for (const auto& f : fs::directory_iterator(d.path())) {
      const std::string ext = f.path().extension().string();
      if (!f.is_regular_file() || (ext != ".dat" && ext != ".txt")) continue;
      auto [it, added] = files.emplace(std::make_pair(dn.substr(6), f.path().stem().string()), f.path().string());
      if (!added && (ext == ".dat") == binary) it->second = f.path().string();  // the preferred form
    }
  }
  if (files.empty()) throw InputError(homol, 0, "holds no Pastis<IMAGE>/<IMAGE>.dat|.txt file");
  auto rank = [&](const std::string& name) {
    for (size_t i = 0; i < order.size(); ++i)
      if (image_file_name(order[i]) == name) return i;
    return order.size();
  };
  auto first = [&](const std::string& a, const std::string& b) {
    const size_t ra = rank(a), rb = rank(b);
    return ra != rb ? ra < rb : a < b;
  };
  std::vector<Matches> out;
  for (const auto& [names, path] : files) {
    const auto& [a, b] = names;
    const bool forward = first(a, b);
    if (!forward && files.count({b, a})) continue;  // read from the other direction
    Matches m = read_micmac_homol(path);
    if (!forward) {
      std::swap(m.image1, m.image2);
      std::swap(m.id1, m.id2);
      Eigen::MatrixXd swapped(m.xy.rows(), 4);
      swapped << m.xy.rightCols(2), m.xy.leftCols(2);
      m.xy = swapped;
    }
    out.push_back(std::move(m));
  }
  return out;
}

}  // namespace tpkit
