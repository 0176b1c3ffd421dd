#include "tpkit/rpc/rpc_bias.hpp"

#include <cmath>
#include <sstream>
#include <vector>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"

namespace tpkit {

BiasModel parse_bias_model(const std::string& s) {
  if (s == "shift") return BiasModel::shift;
  if (s == "drift") return BiasModel::drift;
  if (s == "affine") return BiasModel::affine;
  throw UsageError("--model: expected shift, drift or affine, got '" + s + "'");
}

const char* bias_model_name(BiasModel m) {
  switch (m) {
    case BiasModel::shift: return "shift";
    case BiasModel::drift: return "drift";
    case BiasModel::affine: return "affine";
  }
  return "?";
}

std::array<bool, 6> bias_terms_used(BiasModel m) {
  switch (m) {
    case BiasModel::shift: return {true, false, false, true, false, false};
    case BiasModel::drift: return {true, false, true, true, false, true};
    case BiasModel::affine: return {true, true, true, true, true, true};
  }
  return {};
}

std::vector<double> parse_number_list(const std::string& text, const std::string& option, const std::string& form) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    size_t used = 0;
    double x = 0;
    try {
      x = std::stod(item, &used);
    } catch (...) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(x))
      throw UsageError(option + ": '" + item + "' is not a number (expected " + form + ")");
    v.push_back(x);
  }
  return v;
}

ImageBias parse_image_bias(const std::string& text, const std::string& option) {
  std::vector<double> v = parse_number_list(text, option, "dx,dy[,dxy,dyy[,dxx,dyx]]");
  if (v.size() != 2 && v.size() != 4 && v.size() != 6)
    throw UsageError(option + ": expected 2, 4 or 6 numbers (dx,dy[,dxy,dyy[,dxx,dyx]]), got '" + text + "'");
  ImageBias b;
  b.a[0] = v[0];
  b.b[0] = v[1];
  if (v.size() >= 4) {
    b.a[2] = v[2];
    b.b[2] = v[3];
  }
  if (v.size() == 6) {
    b.a[1] = v[4];
    b.b[1] = v[5];
  }
  return b;
}

void save_bias_table(const std::string& path, const BiasTable& t) {
  std::ostringstream os;
  std::vector<std::string> cols = {"image", "a0", "a1", "a2", "b0", "b1", "b2"};
  cols.insert(cols.end(), t.extra_names.begin(), t.extra_names.end());
  write_header(os, "rpc-bias", 1, t.images, t.meta, cols);
  for (size_t i = 0; i < t.bias.size(); ++i) {
    const ImageBias& b = t.bias[i];
    std::vector<double> rec = {static_cast<double>(i + 1), b.a[0], b.a[1], b.a[2], b.b[0], b.b[1], b.b[2]};
    if (i < t.extra.size()) rec.insert(rec.end(), t.extra[i].begin(), t.extra[i].end());
    write_record(os, rec);
  }
  write_file_atomic(path, os.str());
}

BiasTable read_bias_table(const std::string& path) {
  ReadOptions ro;
  ro.kind = "rpc-bias";
  ro.default_columns = [](size_t) { return std::vector<std::string>{}; };
  TextTable tt = read_table_file(path, ro);
  BiasTable t;
  t.images = tt.images;
  t.meta = tt.meta;
  const char* names[] = {"image", "a0", "a1", "a2", "b0", "b1", "b2"};
  int c[7];
  for (int k = 0; k < 7; ++k) c[k] = tt.require(names[k]);
  t.bias.resize(tt.images.size());
  std::vector<char> seen(tt.images.size(), 0);
  for (size_t r = 0; r < tt.rows.size(); ++r) {
    const auto& row = tt.rows[r];
    double img = row[c[0]];
    if (img != std::floor(img) || img < 1 || img > static_cast<double>(tt.images.size()))
      throw InputError(tt.source, tt.row_line[r], "image " + format_number(img) + " is not one of the file's images");
    size_t i = static_cast<size_t>(img) - 1;
    if (seen[i]) throw InputError(tt.source, tt.row_line[r], "image " + format_number(img) + " given twice");
    seen[i] = 1;
    t.bias[i].a = {row[c[1]], row[c[2]], row[c[3]]};
    t.bias[i].b = {row[c[4]], row[c[5]], row[c[6]]};
  }
  return t;
}

}  // namespace tpkit
