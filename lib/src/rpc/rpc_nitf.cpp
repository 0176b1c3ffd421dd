// See rpc_nitf.hpp. Field offsets and widths of RPC00B (STDI-0002 vol. 1 app. E, table E-22): SUCCESS 1,
// ERR_BIAS 7, ERR_RAND 7, LINE_OFF 6, SAMP_OFF 5, LAT_OFF 8, LONG_OFF 9, HEIGHT_OFF 5, LINE_SCALE 6,
// SAMP_SCALE 5, LAT_SCALE 8, LONG_SCALE 9, HEIGHT_SCALE 5, then 20 each of LINE_NUM, LINE_DEN,
// SAMP_NUM, SAMP_DEN (12 characters each): 81 + 4 x 240 = 1041.
#include "tpkit/rpc/rpc_nitf.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {

constexpr size_t kTreLength = 1041;

// How STDI-0002 writes a numeric field: digits, with a sign (its form starts with +-), a decimal point
// and an exponent (E+d) only where the field's form has them.
struct NumberForm {
  bool sign, point, exponent;
};
constexpr NumberForm kUnsigned{false, false, false}, kUnsignedPoint{false, true, false}, kSigned{true, false, false},
    kSignedPoint{true, true, false}, kCoefficient{true, true, true};

struct ScalarField {
  const char* name;
  size_t offset, width;
  double RpcModel::*member;
  NumberForm form;
};
const ScalarField kFields[] = {
    {"ERR_BIAS", 1, 7, &RpcModel::err_bias, kUnsignedPoint},      {"ERR_RAND", 8, 7, &RpcModel::err_rand, kUnsignedPoint},
    {"LINE_OFF", 15, 6, &RpcModel::line_off, kUnsigned},          {"SAMP_OFF", 21, 5, &RpcModel::samp_off, kUnsigned},
    {"LAT_OFF", 26, 8, &RpcModel::lat_off, kSignedPoint},         {"LONG_OFF", 34, 9, &RpcModel::lon_off, kSignedPoint},
    {"HEIGHT_OFF", 43, 5, &RpcModel::height_off, kSigned},        {"LINE_SCALE", 48, 6, &RpcModel::line_scale, kUnsigned},
    {"SAMP_SCALE", 54, 5, &RpcModel::samp_scale, kUnsigned},      {"LAT_SCALE", 59, 8, &RpcModel::lat_scale, kSignedPoint},
    {"LONG_SCALE", 67, 9, &RpcModel::lon_scale, kSignedPoint},    {"HEIGHT_SCALE", 76, 5, &RpcModel::height_scale, kSigned},
};
struct PolyField {
  const char* name;
  size_t offset;
  RpcPoly RpcModel::*member;
};
const PolyField kPolys[] = {{"LINE_NUM_COEFF", 81, &RpcModel::line_num},
                            {"LINE_DEN_COEFF", 321, &RpcModel::line_den},
                            {"SAMP_NUM_COEFF", 561, &RpcModel::samp_num},
                            {"SAMP_DEN_COEFF", 801, &RpcModel::samp_den}};
// RPC00A's term order mapped to RPC00B's: B term i is A term kRpc00aTerm[i] (GDAL, frmts/nitf/nitfimage.c,
// ticket #2040).
constexpr int kRpc00aTerm[20] = {0, 1, 2, 3, 4, 5, 6, 10, 7, 8, 9, 11, 14, 17, 12, 15, 18, 13, 16, 19};

// True when t is written in `form`: [sign] digits [. digits] [E sign digits], each part only where the
// form has it, at least one digit before the exponent. strtod alone would also take "0x00fa" (250),
// "inf" or "1e3" in a field of digits.
bool in_form(const std::string& t, NumberForm form) {
  size_t i = 0;
  auto sign = [&] {
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
  };
  auto run = [&] {
    const size_t a = i;
    while (i < t.size() && t[i] >= '0' && t[i] <= '9') ++i;
    return i - a;
  };
  if (form.sign) sign();
  size_t digits = run();
  if (form.point && i < t.size() && t[i] == '.') {
    ++i;
    digits += run();
  }
  if (digits == 0) return false;
  if (form.exponent && i < t.size() && t[i] == 'E') {
    ++i;
    sign();
    if (run() == 0) return false;
  }
  return i == t.size();
}

// A field's number; blanks around it are passed over (some producers pad with them), anything else
// outside its form is refused with the field's name and characters.
double field_value(const NitfTre& tre, const std::string& path, size_t offset, size_t width, const std::string& name,
                   NumberForm form) {
  const std::string text = tre.data.substr(offset, width);
  const size_t a = text.find_first_not_of(' ');
  const std::string t = a == std::string::npos ? std::string() : text.substr(a, text.find_last_not_of(' ') - a + 1);
  const bool ok = in_form(t, form);
  const double v = ok ? std::strtod(t.c_str(), nullptr) : 0.0;
  if (!ok || !std::isfinite(v))
    throw InputError(path, 0, tre.tag + " TRE: " + name + " (characters " + std::to_string(offset + 1) + " to " +
                                  std::to_string(offset + width) + ") is '" + text + "', not a number of its form (digits" +
                                  (form.sign ? ", a sign" : "") + (form.point ? ", a decimal point" : "") +
                                  (form.exponent ? ", an exponent E+d" : "") + ")");
  return v;
}

std::string fixed(const char* fmt, double v, size_t width, const char* name) {
  char b[64];
  std::snprintf(b, sizeof b, fmt, v);
  if (std::string(b).size() != width)
    throw InputError(std::string("RPC00B: ") + name + " = " + b + " does not fit its " + std::to_string(width) + " characters");
  return b;
}

// +d.ddddddE+d: 7 significant digits, a one-digit exponent; below 1e-9, 0.
std::string coefficient(double v, const char* name) {
  char b[32];
  std::snprintf(b, sizeof b, "%+.6E", v);
  const std::string s = b;
  const size_t e = s.find('E');
  const int exponent = std::atoi(s.c_str() + e + 1);
  if (v == 0.0 || exponent < -9) return "+0.000000E+0";
  if (exponent > 9) throw InputError(std::string("RPC00B: a coefficient of ") + name + " (" + s + ") is 1e10 or more");
  return s.substr(0, e) + (exponent < 0 ? "E-" : "E+") + std::to_string(std::abs(exponent));
}

// Rounds x up to a multiple of `step` (a scale that still covers its range).
double round_up(double x, double step) { return std::ceil(x / step - 1e-9) * step; }

}  // namespace

RpcModel parse_rpc_tre(const NitfTre& tre, const std::string& path) {
  if (tre.data.size() < kTreLength)
    throw InputError(path, 0, tre.tag + " TRE of " + std::to_string(tre.data.size()) + " characters (" + std::to_string(kTreLength) + " expected)");
  if (tre.data[0] != '1')
    throw InputError(path, 0, tre.tag + " TRE: SUCCESS is '" + tre.data.substr(0, 1) + "': the producer marks the model as not valid");
  RpcModel m;
  for (const auto& f : kFields) m.*(f.member) = field_value(tre, path, f.offset, f.width, f.name, f.form);
  const bool a = tre.tag == "RPC00A";
  for (const auto& p : kPolys)
    for (int i = 0; i < 20; ++i) {
      const int src = a ? kRpc00aTerm[i] : i;
      (m.*(p.member))[i] =
          field_value(tre, path, p.offset + 12 * src, 12, std::string(p.name) + "_" + std::to_string(src + 1), kCoefficient);
    }
  for (const auto& f : kFields)
    if (std::string(f.name).find("SCALE") != std::string::npos && !(m.*(f.member) > 0))
      throw InputError(path, 0, tre.tag + " TRE: " + f.name + " is " + std::to_string(m.*(f.member)) + " (a scale must be > 0)");
  return m;
}

std::optional<RpcModel> read_rpc_nitf(const NitfImage& image) {
  for (const char* tag : {"RPC00B", "RPC00A"}) {
    // a second TRE of the tag: the same bytes say nothing new; other bytes are another model, and which
    // one is the image's is not guessed
    const NitfTre* first = nullptr;
    for (const auto& t : image.tres) {
      if (t.tag != tag) continue;
      if (!first)
        first = &t;
      else if (t.data != first->data)
        throw InputError(image.path, 0, std::string("two ") + tag + " TREs that disagree (at bytes " + std::to_string(first->offset) +
                                            " and " + std::to_string(t.offset) + "): which model is the image's is not guessed");
    }
    if (first) return parse_rpc_tre(*first, image.path);
  }
  return std::nullopt;
}

RpcTre format_rpc00b_tre(const RpcModel& m) {
  // the normalization as the fields hold it: offsets rounded, scales rounded outward over the shift
  RpcModel to = m;
  to.line_off = std::round(m.line_off);
  to.samp_off = std::round(m.samp_off);
  to.height_off = std::round(m.height_off);
  to.lat_off = std::round(m.lat_off * 1e4) / 1e4;
  to.lon_off = std::round(m.lon_off * 1e4) / 1e4;
  to.line_scale = round_up(m.line_scale + std::abs(m.line_off - to.line_off), 1.0);
  to.samp_scale = round_up(m.samp_scale + std::abs(m.samp_off - to.samp_off), 1.0);
  to.height_scale = round_up(m.height_scale + std::abs(m.height_off - to.height_off), 1.0);
  to.lat_scale = round_up(m.lat_scale + std::abs(m.lat_off - to.lat_off), 1e-4);
  to.lon_scale = round_up(m.lon_scale + std::abs(m.lon_off - to.lon_off), 1e-4);
  if (to.line_off < 0 || to.samp_off < 0)
    throw InputError("RPC00B: LINE_OFF " + std::to_string(m.line_off) + ", SAMP_OFF " + std::to_string(m.samp_off) +
                     ": the TRE holds offsets of 0 or more pixels only");
  const RpcModel r = renormalized_rpc(m, to);
  std::string d = "1";
  d += fixed("%07.2f", std::max(0.0, m.err_bias), 7, "ERR_BIAS");
  d += fixed("%07.2f", std::max(0.0, m.err_rand), 7, "ERR_RAND");
  d += fixed("%06.0f", to.line_off, 6, "LINE_OFF") + fixed("%05.0f", to.samp_off, 5, "SAMP_OFF");
  d += fixed("%+08.4f", to.lat_off, 8, "LAT_OFF") + fixed("%+09.4f", to.lon_off, 9, "LONG_OFF");
  d += fixed("%+05.0f", to.height_off, 5, "HEIGHT_OFF");
  d += fixed("%06.0f", to.line_scale, 6, "LINE_SCALE") + fixed("%05.0f", to.samp_scale, 5, "SAMP_SCALE");
  d += fixed("%+08.4f", to.lat_scale, 8, "LAT_SCALE") + fixed("%+09.4f", to.lon_scale, 9, "LONG_SCALE");
  d += fixed("%+05.0f", to.height_scale, 5, "HEIGHT_SCALE");
  for (const auto& p : kPolys)
    for (double c : r.*(p.member)) d += coefficient(c, p.name);
  RpcTre out;
  out.tre = NitfTre{"RPC00B", d};
  out.model = parse_rpc_tre(out.tre, "RPC00B");
  // what the fixed precision changed, over the validity volume
  const RpcFitVolume v = rpc_volume(m);
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j)
      for (int k = 0; k <= 4; ++k) {
        const double lon = v.lon0 + (v.lon1 - v.lon0) * i / 20, lat = v.lat0 + (v.lat1 - v.lat0) * j / 20;
        const double h = v.h0 + (v.h1 - v.h0) * k / 4;
        out.max_change_px = std::max(out.max_change_px, (m.project(lon, lat, h) - out.model.project(lon, lat, h)).norm());
      }
  return out;
}

}  // namespace tpkit
