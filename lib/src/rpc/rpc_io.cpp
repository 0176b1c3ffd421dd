#include "tpkit/rpc/rpc_io.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <set>
#include <sstream>
#include <tuple>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/nitf_image.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tiff_image.hpp"
#include "tpkit/rpc/rpc_nitf.hpp"

namespace tpkit {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------- shared helpers

// The whole of an RPC file: a regular file or a pipe, at most kMaxRpcFile bytes (a model is a few KB; a
// device such as /dev/zero or a wrong path to an image must not fill memory), without a UTF-8 byte order
// mark (Windows editors put one before the first key).
constexpr size_t kMaxRpcFile = size_t(16) << 20;
std::string read_whole(const std::string& path) {
  std::ifstream in = open_input_file(path, InputKind::file, true);
  std::string s;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    s.append(buf, static_cast<size_t>(in.gcount()));
    if (s.size() > kMaxRpcFile)
      throw InputError(path, 0, "larger than " + std::to_string(kMaxRpcFile >> 20) + " MiB: not an RPC model");
  }
  if (in.bad()) throw InputError(path, 0, "read error");
  if (s.compare(0, 3, "\xEF\xBB\xBF") == 0) s.erase(0, 3);
  return s;
}

std::string trim(const std::string& s) {
  size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

// A decimal number (an optional '+' allowed, as in Ikonos files); false for anything else.
bool parse_double(std::string s, double& v) {
  s = trim(s);
  if (!s.empty() && s[0] == '+') s.erase(0, 1);
  if (s.empty()) return false;
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(v);
}

double number_or_throw(const std::string& text, const std::string& file, long line, const std::string& key) {
  double v;
  if (!parse_double(text, v)) throw InputError(file, line, key + ": '" + trim(text) + "' is not a number");
  return v;
}

// `count` numbers in one value, separated by blanks or commas (GDAL's RPC metadata, as GDALExtractRPCInfo
// splits it; DIMAP v1's rational functions).
std::vector<double> numbers_or_throw(const std::string& text, const std::string& file, long line, const std::string& key,
                                     size_t count) {
  static const char* kSeparators = " \t\r\n,";
  std::vector<double> out;
  for (size_t i = text.find_first_not_of(kSeparators); i != std::string::npos; i = text.find_first_not_of(kSeparators, i)) {
    const size_t e = text.find_first_of(kSeparators, i);
    out.push_back(number_or_throw(text.substr(i, e - i), file, line, key));
    i = e;
    if (i == std::string::npos) break;
  }
  if (out.size() != count)
    throw InputError(file, line, key + ": " + std::to_string(out.size()) + " coefficients instead of " + std::to_string(count));
  return out;
}

// The named scalar fields of RPC00B, in the order of the GeoTIFF tag after ERR_BIAS, ERR_RAND.
struct Field {
  const char* txt;   // GDAL / Ikonos key (also GDAL's RPC metadata domain)
  const char* rpb;   // DigitalGlobe key
  const char* geom;  // OSSIM keyword
  double RpcModel::*member;
};
const Field kScalars[] = {
    {"ERR_BIAS", "errBias", "bias_error", &RpcModel::err_bias},
    {"ERR_RAND", "errRand", "rand_error", &RpcModel::err_rand},
    {"LINE_OFF", "lineOffset", "line_off", &RpcModel::line_off},
    {"SAMP_OFF", "sampOffset", "samp_off", &RpcModel::samp_off},
    {"LAT_OFF", "latOffset", "lat_off", &RpcModel::lat_off},
    {"LONG_OFF", "longOffset", "long_off", &RpcModel::lon_off},
    {"HEIGHT_OFF", "heightOffset", "height_off", &RpcModel::height_off},
    {"LINE_SCALE", "lineScale", "line_scale", &RpcModel::line_scale},
    {"SAMP_SCALE", "sampScale", "samp_scale", &RpcModel::samp_scale},
    {"LAT_SCALE", "latScale", "lat_scale", &RpcModel::lat_scale},
    {"LONG_SCALE", "longScale", "long_scale", &RpcModel::lon_scale},
    {"HEIGHT_SCALE", "heightScale", "height_scale", &RpcModel::height_scale},
};
// ERR_BIAS and ERR_RAND may be absent from every form (0 then); the other fields are required.
bool optional_field(const Field& f) { return f.member == &RpcModel::err_bias || f.member == &RpcModel::err_rand; }
struct PolyField {
  const char* txt;
  const char* rpb;
  const char* geom;
  RpcPoly RpcModel::*member;
};
const PolyField kPolys[] = {
    {"LINE_NUM_COEFF", "lineNumCoef", "line_num_coeff", &RpcModel::line_num},
    {"LINE_DEN_COEFF", "lineDenCoef", "line_den_coeff", &RpcModel::line_den},
    {"SAMP_NUM_COEFF", "sampNumCoef", "samp_num_coeff", &RpcModel::samp_num},
    {"SAMP_DEN_COEFF", "sampDenCoef", "samp_den_coeff", &RpcModel::samp_den},
};

bool zero(const RpcPoly& p) {
  for (double c : p)
    if (c != 0) return false;
  return true;
}

// Checks what makes a model unusable, whatever its form: a value that is not finite (the tag holds raw
// doubles), a scale that is not positive, offsets off the globe, an all-zero numerator or denominator, and
// a denominator that vanishes or changes sign in the model's validity box (the normalized cube [-1, 1]^3,
// sampled on a 9^3 grid): a pole there sends every point near it anywhere.
void check_model(const RpcModel& m, const std::string& file) {
  for (double v : rpc_tag_values(m))
    if (!std::isfinite(v)) throw InputError(file, 0, "an RPC value is not finite (" + format_number(v) + ")");
  const std::pair<const char*, double> scales[] = {{"LINE_SCALE", m.line_scale}, {"SAMP_SCALE", m.samp_scale},
                                                   {"LAT_SCALE", m.lat_scale},   {"LONG_SCALE", m.lon_scale},
                                                   {"HEIGHT_SCALE", m.height_scale}};
  for (const auto& [name, s] : scales)
    if (!(s > 0)) throw InputError(file, 0, std::string(name) + " is " + format_number(s) + ": an RPC scale must be positive");
  if (!(std::fabs(m.lat_off) <= 90)) throw InputError(file, 0, "LAT_OFF " + format_number(m.lat_off) + " is not a latitude");
  if (!(std::fabs(m.lon_off) <= 360)) throw InputError(file, 0, "LONG_OFF " + format_number(m.lon_off) + " is not a longitude");
  if (!(std::fabs(m.lat_off) + m.lat_scale <= 90.5))
    throw InputError(file, 0, "LAT_OFF " + format_number(m.lat_off) + " +- LAT_SCALE " + format_number(m.lat_scale) + " leaves the globe");
  if (zero(m.line_den) || zero(m.samp_den)) throw InputError(file, 0, "an RPC denominator is all zeros");
  if (zero(m.line_num) || zero(m.samp_num)) throw InputError(file, 0, "an RPC numerator is all zeros");
  for (const auto& [name, den] : {std::make_pair("LINE_DEN_COEFF", &m.line_den), std::make_pair("SAMP_DEN_COEFF", &m.samp_den)}) {
    double lo = INFINITY, hi = -INFINITY;
    for (int a = 0; a < 9; ++a)
      for (int b = 0; b < 9; ++b)
        for (int c = 0; c < 9; ++c) {
          double t[20];
          rpc_terms(-1 + a * 0.25, -1 + b * 0.25, -1 + c * 0.25, t);
          const double d = rpc_eval(*den, t);
          lo = std::min(lo, d);
          hi = std::max(hi, d);
        }
    if (lo * hi <= 0 || std::min(std::fabs(lo), std::fabs(hi)) < 1e-6 * std::max(std::fabs(lo), std::fabs(hi)))
      throw InputError(file, 0, std::string(name) + ": the denominator vanishes in the model's validity box (from " +
                                    format_number(lo) + " to " + format_number(hi) + "): a pole");
  }
}

std::string join_poly(const RpcPoly& p, const char* sep) {
  std::string s;
  for (int i = 0; i < 20; ++i) s += (i ? sep : "") + format_number(p[i]);
  return s;
}

// ---------------------------------------------------------------- GDAL / Ikonos text

RpcModel parse_txt(const std::string& text, const std::string& file) {
  std::map<std::string, std::pair<double, long>> kv;
  std::istringstream in(text);
  std::string line;
  long no = 0;
  while (std::getline(in, line)) {
    ++no;
    std::string t = trim(line);
    if (t.empty()) continue;
    size_t colon = t.find(':');
    if (colon == std::string::npos) throw InputError(file, no, "expected 'KEY: value'");
    std::string key = trim(t.substr(0, colon)), value = trim(t.substr(colon + 1));
    if (key.empty()) throw InputError(file, no, "expected 'KEY: value'");
    // a trailing unit word ("pixels", "degrees", "meters") is allowed
    size_t sp = value.find_last_of(" \t");
    if (sp != std::string::npos && std::isalpha(static_cast<unsigned char>(value[sp + 1])))
      value = trim(value.substr(0, sp));
    double v = number_or_throw(value, file, no, key);
    if (!kv.emplace(key, std::make_pair(v, no)).second) throw InputError(file, no, key + " given twice");
  }
  RpcModel m;
  auto get = [&](const std::string& key, bool required, double& out) {
    auto it = kv.find(key);
    if (it == kv.end()) {
      if (required) throw InputError(file, 0, "missing " + key);
      return;
    }
    out = it->second.first;
  };
  for (const auto& f : kScalars) get(f.txt, !optional_field(f), m.*f.member);
  for (const auto& p : kPolys)
    for (int i = 0; i < 20; ++i) get(std::string(p.txt) + "_" + std::to_string(i + 1), true, (m.*p.member)[i]);
  check_model(m, file);
  return m;
}

// ---------------------------------------------------------------- DigitalGlobe .RPB

struct Token {
  std::string text;
  long line;
  bool quoted;
};

std::vector<Token> tokenize_rpb(const std::string& text, const std::string& file) {
  std::vector<Token> out;
  long line = 1;
  size_t i = 0;
  while (i < text.size()) {
    char c = text[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (c == '=' || c == ';' || c == '(' || c == ')' || c == ',') {
      out.push_back({std::string(1, c), line, false});
      ++i;
    } else if (c == '"') {
      size_t e = text.find('"', i + 1);
      if (e == std::string::npos || text.find('\n', i) < e) throw InputError(file, line, "unterminated string");
      out.push_back({text.substr(i + 1, e - i - 1), line, true});
      i = e + 1;
    } else {
      size_t e = i;
      while (e < text.size() && !std::isspace(static_cast<unsigned char>(text[e])) && std::string("=;(),\"").find(text[e]) == std::string::npos)
        ++e;
      out.push_back({text.substr(i, e - i), line, false});
      i = e;
    }
  }
  return out;
}

RpcModel parse_rpb(const std::string& text, const std::string& file) {
  auto tok = tokenize_rpb(text, file);
  size_t i = 0;
  auto at = [&](size_t k) -> const Token& {
    if (k >= tok.size())
      throw InputError(file, tok.empty() ? 1 : tok.back().line, "unexpected end of file (missing END;)");
    return tok[k];
  };
  auto expect = [&](const char* s) {
    const Token& t = at(i);
    if (t.quoted || t.text != s) throw InputError(file, t.line, std::string("expected '") + s + "', got '" + t.text + "'");
    ++i;
  };
  std::map<std::string, std::pair<std::vector<double>, long>> image;
  bool in_image = false, ended = false;
  while (!ended) {
    const Token& name = at(i++);
    if (name.quoted) throw InputError(file, name.line, "expected a name, got a string");
    if (name.text == "END") {
      expect(";");
      ended = true;
      break;
    }
    expect("=");
    if (name.text == "BEGIN_GROUP" || name.text == "END_GROUP") {
      const Token& g = at(i++);
      if (name.text == "BEGIN_GROUP") {
        if (in_image) throw InputError(file, name.line, "nested group");
        if (g.text != "IMAGE") throw InputError(file, g.line, "unknown group '" + g.text + "' (expected IMAGE)");
        in_image = true;
      } else {
        if (!in_image || g.text != "IMAGE") throw InputError(file, g.line, "END_GROUP without BEGIN_GROUP = IMAGE");
        in_image = false;
      }
      if (i < tok.size() && tok[i].text == ";") ++i;
      continue;
    }
    std::vector<double> values;
    if (at(i).text == "(" && !at(i).quoted) {
      ++i;
      while (true) {
        const Token& v = at(i++);
        values.push_back(number_or_throw(v.text, file, v.line, name.text));
        const Token& sep = at(i++);
        if (sep.text == ")") break;
        if (sep.text != ",") throw InputError(file, sep.line, "expected ',' or ')' in " + name.text);
      }
    } else {
      const Token& v = at(i++);
      if (in_image) values.push_back(number_or_throw(v.text, file, v.line, name.text));
    }
    expect(";");
    if (in_image && !image.emplace(name.text, std::make_pair(values, name.line)).second)
      throw InputError(file, name.line, name.text + " given twice");
  }
  if (in_image) throw InputError(file, at(i - 1).line, "END before END_GROUP = IMAGE");
  if (i != tok.size()) throw InputError(file, tok[i].line, "text after END;");
  RpcModel m;
  for (const auto& f : kScalars) {
    auto it = image.find(f.rpb);
    if (it == image.end()) {
      if (optional_field(f)) continue;
      throw InputError(file, 0, std::string("missing IMAGE.") + f.rpb);
    }
    if (it->second.first.size() != 1) throw InputError(file, it->second.second, std::string(f.rpb) + ": expected one value");
    m.*f.member = it->second.first[0];
  }
  for (const auto& p : kPolys) {
    auto it = image.find(p.rpb);
    if (it == image.end()) throw InputError(file, 0, std::string("missing IMAGE.") + p.rpb);
    if (it->second.first.size() != 20)
      throw InputError(file, it->second.second, std::string(p.rpb) + ": " + std::to_string(it->second.first.size()) +
                                                     " coefficients instead of 20");
    std::copy(it->second.first.begin(), it->second.first.end(), (m.*p.member).begin());
  }
  check_model(m, file);
  return m;
}

// ---------------------------------------------------------------- XML (DIMAP, GDAL's .aux.xml)

// An element open on the way from the document's root to a leaf: its name, its attributes, its tag's line
// and byte offset (which tells two elements of the same name and line apart).
struct XmlOpen {
  std::string name;
  std::map<std::string, std::string> attributes;
  long line;
  size_t at;
};

// Text or an attribute value with its references replaced by their characters: XML's five predefined
// entities and character references (&#45; &#x2d;, written as UTF-8). Any other '&' (an entity a DTD
// would define, a bare '&') is refused: a document whose text is not what it says is not guessed.
std::string xml_unescape(const std::string& s, const std::string& file, long line) {
  static const std::pair<const char*, char> kEntities[] = {
      {"lt", '<'}, {"gt", '>'}, {"quot", '"'}, {"apos", '\''}, {"amp", '&'}};
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '&') {
      out += s[i];
      continue;
    }
    const size_t semi = s.find(';', i);
    const std::string ref = semi == std::string::npos ? std::string() : s.substr(i + 1, semi - i - 1);
    auto refused = [&]() -> InputError {
      return InputError(file, line, "'" + s.substr(i, std::min<size_t>(12, s.size() - i)) +
                                        "': not one of XML's five entities (&lt; &gt; &amp; &quot; &apos;) or a character "
                                        "reference (&#45; &#x2d;)");
    };
    bool known = false;
    for (const auto& [name, c] : kEntities)
      if (ref == name) {
        out += c;
        known = true;
      }
    if (!known) {
      const bool hex = ref.size() > 2 && ref[1] == 'x';
      const std::string digits = ref.size() > 1 && ref[0] == '#' ? ref.substr(hex ? 2 : 1) : std::string();
      if (digits.empty() || digits.size() > 8 ||
          digits.find_first_not_of(hex ? "0123456789abcdefABCDEF" : "0123456789") != std::string::npos)
        throw refused();
      const unsigned long c = std::stoul(digits, nullptr, hex ? 16 : 10);
      // XML's Char production: a reference to anything else is not well-formed
      if (!(c == 0x9 || c == 0xA || c == 0xD || (c >= 0x20 && c <= 0xD7FF) || (c >= 0xE000 && c <= 0xFFFD) ||
            (c >= 0x10000 && c <= 0x10FFFF)))
        throw refused();
      if (c < 0x80) {
        out += static_cast<char>(c);
      } else if (c < 0x800) {
        out += static_cast<char>(0xC0 | (c >> 6));
        out += static_cast<char>(0x80 | (c & 0x3F));
      } else if (c < 0x10000) {
        out += static_cast<char>(0xE0 | (c >> 12));
        out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (c & 0x3F));
      } else {
        out += static_cast<char>(0xF0 | (c >> 18));
        out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
        out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (c & 0x3F));
      }
    }
    i = semi;
  }
  return out;
}

// The attributes (name="value" or name='value') written after an element's name in its start tag.
std::map<std::string, std::string> xml_attributes(const std::string& s, const std::string& element, const std::string& file,
                                                  long line) {
  std::map<std::string, std::string> out;
  const char* blank = " \t\r\n";
  for (size_t i = s.find_first_not_of(blank); i != std::string::npos; i = s.find_first_not_of(blank, i)) {
    const size_t eq = s.find('=', i);
    const size_t q = eq == std::string::npos ? eq : s.find_first_not_of(blank, eq + 1);
    const size_t end = q == std::string::npos || (s[q] != '"' && s[q] != '\'') ? std::string::npos : s.find(s[q], q + 1);
    const std::string name = end == std::string::npos ? std::string() : trim(s.substr(i, eq - i));
    if (name.empty() || name.find_first_of(blank) != std::string::npos)
      throw InputError(file, line, "malformed attributes in <" + element + ">");
    out[name] = xml_unescape(s.substr(q + 1, end - q - 1), file, line);
    i = end + 1;
  }
  return out;
}

// Walks an XML document, calling leaf(path, text, line) for every element without child elements, in
// document order: `path` the elements from the root down to it, `text` its trimmed text (references
// replaced, CDATA sections taken as they are), `line` the line of its end tag. Comments, processing
// instructions and declarations are skipped; unbalanced or unterminated markup is refused with its line.
using XmlLeafVisitor = std::function<void(const std::vector<XmlOpen>& path, const std::string& text, long line)>;
void xml_walk(const std::string& s, const std::string& file, const XmlLeafVisitor& leaf) {
  std::vector<XmlOpen> stack;
  std::string text;
  bool had_child = false;
  long line = 1;
  size_t i = 0;
  auto count_lines = [&](size_t a, size_t b) {
    for (size_t k = a; k < b && k < s.size(); ++k) line += s[k] == '\n';
  };
  while (i < s.size()) {
    if (s[i] != '<') {
      size_t e = s.find('<', i);
      if (e == std::string::npos) e = s.size();
      text += xml_unescape(s.substr(i, e - i), file, line);
      count_lines(i, e);
      i = e;
      continue;
    }
    long tag_line = line;
    if (s.compare(i, 9, "<![CDATA[") == 0) {  // text as it is, references and all
      const size_t e = s.find("]]>", i + 9);
      if (e == std::string::npos) throw InputError(file, tag_line, "unterminated CDATA section");
      text += s.substr(i + 9, e - i - 9);
      count_lines(i, e + 3);
      i = e + 3;
      continue;
    }
    auto skip_to = [&](const char* end) {
      size_t e = s.find(end, i);
      if (e == std::string::npos) throw InputError(file, tag_line, "unterminated markup");
      count_lines(i, e + std::strlen(end));
      i = e + std::strlen(end);
    };
    if (s.compare(i, 4, "<!--") == 0) {
      skip_to("-->");
      continue;
    }
    if (s.compare(i, 2, "<?") == 0) {
      skip_to("?>");
      continue;
    }
    if (s.compare(i, 2, "<!") == 0) {
      skip_to(">");
      continue;
    }
    // the tag ends at the first '>' outside its quoted attribute values (where '>' may stand)
    size_t e = i + 1;
    char quote = 0;
    for (; e < s.size() && (quote || s[e] != '>'); ++e)
      if (s[e] == '"' || s[e] == '\'') quote = quote == s[e] ? 0 : quote ? quote : s[e];
    if (quote) e = s.find('>', i);  // a quote never closed: its attributes are refused as malformed below
    if (e >= s.size()) throw InputError(file, tag_line, "unterminated tag");
    const size_t tag_at = i;
    std::string tag = s.substr(i + 1, e - i - 1);
    count_lines(i, e + 1);
    i = e + 1;
    bool closing = !tag.empty() && tag[0] == '/';
    bool empty = !tag.empty() && tag.back() == '/';
    std::string body = tag.substr(closing ? 1 : 0);
    if (empty) body.pop_back();
    const size_t name_end = body.find_first_of(" \t\r\n");
    std::string name = body.substr(0, name_end);
    if (name.empty()) throw InputError(file, tag_line, "empty tag name");
    if (closing) {
      if (stack.empty() || stack.back().name != name)
        throw InputError(file, tag_line, "</" + name + "> does not close <" + (stack.empty() ? "" : stack.back().name) + ">");
      if (!had_child) leaf(stack, trim(text), tag_line);
      stack.pop_back();
      had_child = true;
      text.clear();
    } else if (empty) {
      had_child = true;
    } else {
      stack.push_back({name, xml_attributes(name_end == std::string::npos ? "" : body.substr(name_end), name, file, tag_line),
                       tag_line, tag_at});
      had_child = false;
      text.clear();
    }
  }
  if (!stack.empty()) throw InputError(file, line, "end of file inside <" + stack.back().name + ">");
}

// Leaf elements of an XML document: path "A.B.C" (element names from the root's child down) -> text, line.
struct XmlLeaf {
  std::string text;
  long line;
  long repeated_at = 0;  // the line of a second leaf of the same path (0: none)
};
// `also`, when given, sees every leaf too.
std::map<std::string, XmlLeaf> xml_leaves(const std::string& s, const std::string& file,
                                          const XmlLeafVisitor& also = nullptr) {
  std::map<std::string, XmlLeaf> out;
  xml_walk(s, file, [&](const std::vector<XmlOpen>& path, const std::string& text, long line) {
    if (also) also(path, text, line);
    std::string p;
    for (size_t k = 1; k < path.size(); ++k) p += (k > 1 ? "." : "") + path[k].name;
    auto [it, fresh] = out.emplace(p, XmlLeaf{text, line});
    if (!fresh && !it->second.repeated_at) it->second.repeated_at = line;
  });
  if (out.empty()) throw InputError(file, 1, "not an XML document");
  return out;
}

// ---------------------------------------------------------------- DIMAP XML

// DIMAP pixel offsets <-> tpkit's: the number is read in extended precision and the image's origin (the
// number of the top-left pixel's centre: 1 in DIMAP v1/v2, FIRST_COL / FIRST_ROW of the
// ImagetoGround_Validity_Domain in DIMAP v3, 0 or 1) subtracted before rounding to double, so that every
// double offset has a decimal that reads back to it exactly.
bool dimap_offset_value(const std::string& text, double& v, long double origin = 1.0L) {
  std::string t = trim(text);
  if (!parse_double(t, v)) return false;  // a decimal number (strtold alone would take "0x1F4" too)
  char* end = nullptr;
  long double x = std::strtold(t.c_str(), &end);
  if (end != t.c_str() + t.size()) return false;
  v = static_cast<double>(x - origin);
  return std::isfinite(v);
}
std::string dimap_offset(double tpkit_off) {
  std::string s = format_number(tpkit_off + 1.0);
  double back;
  if (dimap_offset_value(s, back) && back == tpkit_off) return s;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.21Lg", static_cast<long double>(tpkit_off) + 1.0L);
  return buf;
}

// The RPC part of a DIMAP document: its leaves below the RPC element (Global_RFM, else
// Rational_Function_Model, where GDAL also looks), named relative to it.
struct DimapRpc {
  std::map<std::string, XmlLeaf> leaves;
  std::string base;  // "...Global_RFM."
  std::string file;

  // The first of `names` present (nullptr: none); a leaf given twice is refused.
  const std::pair<const std::string, XmlLeaf>* find(const std::vector<std::string>& names) const {
    for (const auto& n : names) {
      auto it = leaves.find(base + n);
      if (it == leaves.end()) continue;
      if (it->second.repeated_at)
        throw InputError(file, it->second.repeated_at,
                         it->first + " given twice (first at line " + std::to_string(it->second.line) + ")");
      return &*it;
    }
    return nullptr;
  }
  // The number of the first of `names` present; false when none is (an InputError when `required`).
  bool value(const std::vector<std::string>& names, bool required, double& out) const {
    auto* e = find(names);
    if (!e) {
      if (required) throw InputError(file, 0, "missing " + base + names[0]);
      return false;
    }
    out = number_or_throw(e->second.text, file, e->second.line, e->first);
    return true;
  }
  // A pixel offset (SAMP_OFF, LINE_OFF) counted from `origin` (the number of the top-left pixel's centre),
  // as tpkit's (dimap_offset_value).
  void pixel_offset(const std::string& name, long double origin, double& out) const {
    auto* e = find({name});
    if (!e) throw InputError(file, 0, "missing " + base + name);
    if (!dimap_offset_value(e->second.text, out, origin))
      throw InputError(file, e->second.line, e->first + ": '" + e->second.text + "' is not a number");
  }
};

// The RPC elements a DIMAP document may hold its model in, in the order they are looked for.
const char* const kDimapRpcElements[] = {"Global_RFM", "Rational_Function_Model"};

std::string dimap_rpc_base(const std::map<std::string, XmlLeaf>& leaves) {
  for (const std::string element : kDimapRpcElements)
    for (const auto& kv : leaves) {
      const size_t k = kv.first.find(element + ".");
      if (k != std::string::npos) return kv.first.substr(0, k + element.size() + 1);
    }
  return "";
}

// DIMAP v2 (Pléiades, SPOT 6/7) and v3 (Pléiades Neo): one element per coefficient, Inverse_Model /
// GroundtoImage_Values and Direct_Model / ImagetoGround_Values, the normalization in RFM_Validity.
RpcModel dimap_v2_model(const DimapRpc& d) {
  RpcModel m;
  const char* kInverse[] = {"Inverse_Model.", "GroundtoImage_Values."};
  const char* kDirect[] = {"Direct_Model.", "ImagetoGround_Values."};
  for (const auto& p : kPolys)
    for (int i = 0; i < 20; ++i) {
      std::string n = std::string(p.txt) + "_" + std::to_string(i + 1);
      d.value({kInverse[0] + n, kInverse[1] + n}, true, (m.*p.member)[i]);
    }
  // direct model: Pléiades names its outputs SAMP (longitude) and LINE (latitude), Pléiades Neo LON and LAT
  struct DirectPoly {
    const char* phr;
    const char* pneo;
    RpcPoly RpcModel::*member;
  };
  const DirectPoly direct[] = {{"SAMP_NUM_COEFF", "LON_NUM_COEFF", &RpcModel::lon_num},
                               {"SAMP_DEN_COEFF", "LON_DEN_COEFF", &RpcModel::lon_den},
                               {"LINE_NUM_COEFF", "LAT_NUM_COEFF", &RpcModel::lat_num},
                               {"LINE_DEN_COEFF", "LAT_DEN_COEFF", &RpcModel::lat_den}};
  int found = 0;
  for (const auto& dp : direct)
    for (int i = 0; i < 20; ++i) {
      std::string k = "_" + std::to_string(i + 1);
      found += d.value({kDirect[0] + std::string(dp.phr) + k, kDirect[1] + std::string(dp.pneo) + k,
                        kDirect[0] + std::string(dp.pneo) + k},
                       false, (m.*dp.member)[i]);
    }
  if (found != 0 && found != 80)
    throw InputError(d.file, 0, "incomplete Direct_Model (" + std::to_string(found) + " of 80 coefficients)");
  m.has_direct = found == 80;
  const std::pair<const char*, double RpcModel::*> scalars[] = {
      {"LONG_SCALE", &RpcModel::lon_scale},  {"LONG_OFF", &RpcModel::lon_off},       {"LAT_SCALE", &RpcModel::lat_scale},
      {"LAT_OFF", &RpcModel::lat_off},       {"HEIGHT_SCALE", &RpcModel::height_scale}, {"HEIGHT_OFF", &RpcModel::height_off},
      {"SAMP_SCALE", &RpcModel::samp_scale}, {"LINE_SCALE", &RpcModel::line_scale}};
  for (const auto& [n, member] : scalars) d.value({std::string("RFM_Validity.") + n}, true, m.*member);
  // DIMAP v2: the centre of the top-left pixel is (1, 1); DIMAP v3 (Pléiades Neo) says which, 0 or 1, in
  // FIRST_COL and FIRST_ROW of its ImagetoGround_Validity_Domain (GDAL reads it so, taking FIRST_COL for
  // both axes; here each axis its own); tpkit and RPC00B: (0, 0)
  auto origin = [&](const char* key) {
    auto* e = d.find({std::string("RFM_Validity.ImagetoGround_Validity_Domain.") + key});
    if (!e) return 1.0L;
    const double v = number_or_throw(e->second.text, d.file, e->second.line, e->first);
    if (v != 0 && v != 1)
      throw InputError(d.file, e->second.line, e->first + ": " + e->second.text + " (the first pixel is numbered 0 or 1)");
    return static_cast<long double>(v);
  };
  d.pixel_offset("RFM_Validity.SAMP_OFF", origin("FIRST_COL"), m.samp_off);
  d.pixel_offset("RFM_Validity.LINE_OFF", origin("FIRST_ROW"), m.line_off);
  return m;
}

// DIMAP v1 (the first Pléiades products: PHRDIMAP.XML, METADATA_FORMAT DIMAP_PHR, profile version 1.x;
// CNES shareloc's rpc_readers.py reads it so): each rational function is one list of 40 numbers, its
// numerator's 20 coefficients then its denominator's, in RPC00B's term order (Inverse_Model F_COL: the
// sample, F_ROW: the line; Direct_Model F_LON, F_LAT of normalized sample, line, height as v2's direct
// model), and RFM_Validity holds each normalization as A (scale) and B (offset) of Lon, Lat, Alt, Col
// and Row. Pixels are numbered from 1, as in v2 (PIXEL_ORIGIN 1): Col.B and Row.B are tpkit's plus 1.
RpcModel dimap_v1_model(const DimapRpc& d) {
  RpcModel m;
  struct Rational {
    const char* name;
    RpcPoly RpcModel::*num;
    RpcPoly RpcModel::*den;
    bool direct;
  };
  const Rational functions[] = {{"Inverse_Model.F_COL", &RpcModel::samp_num, &RpcModel::samp_den, false},
                                {"Inverse_Model.F_ROW", &RpcModel::line_num, &RpcModel::line_den, false},
                                {"Direct_Model.F_LON", &RpcModel::lon_num, &RpcModel::lon_den, true},
                                {"Direct_Model.F_LAT", &RpcModel::lat_num, &RpcModel::lat_den, true}};
  int direct = 0;
  for (const auto& f : functions) {
    auto* e = d.find({f.name});
    if (!e) {
      if (!f.direct) throw InputError(d.file, 0, "missing " + d.base + f.name);
      continue;
    }
    const std::vector<double> c = numbers_or_throw(e->second.text, d.file, e->second.line, e->first, 40);
    std::copy(c.begin(), c.begin() + 20, (m.*f.num).begin());
    std::copy(c.begin() + 20, c.end(), (m.*f.den).begin());
    direct += f.direct;
  }
  if (direct == 1) throw InputError(d.file, 0, "incomplete Direct_Model (F_LON and F_LAT go together)");
  m.has_direct = direct == 2;
  const std::tuple<const char*, double RpcModel::*, double RpcModel::*> axes[] = {
      {"Lon", &RpcModel::lon_scale, &RpcModel::lon_off},
      {"Lat", &RpcModel::lat_scale, &RpcModel::lat_off},
      {"Alt", &RpcModel::height_scale, &RpcModel::height_off},
      {"Col", &RpcModel::samp_scale, &RpcModel::samp_off},
      {"Row", &RpcModel::line_scale, &RpcModel::line_off}};
  for (const auto& [axis, scale, off] : axes) {
    const std::string n = std::string("RFM_Validity.") + axis;
    d.value({n + ".A"}, true, m.*scale);
    if (off == &RpcModel::samp_off || off == &RpcModel::line_off)
      d.pixel_offset(n + ".B", 1.0L, m.*off);
    else
      d.value({n + ".B"}, true, m.*off);
  }
  return m;
}

RpcModel parse_dimap(const std::string& text, const std::string& file) {
  // the RPC elements met (name -> their tags' byte offsets and lines): a second one is a second model,
  // and which is the image's is not guessed (a path's leaves seen twice are refused too, but the second
  // element may stand elsewhere in the document)
  std::map<std::string, std::map<size_t, long>> rpc_elements;
  DimapRpc d{xml_leaves(text, file,
                        [&](const std::vector<XmlOpen>& path, const std::string&, long) {
                          for (const auto& e : path)
                            for (const char* name : kDimapRpcElements)
                              if (e.name == name) rpc_elements[name].emplace(e.at, e.line);
                        }),
             "", file};
  d.base = dimap_rpc_base(d.leaves);
  if (d.base.empty()) throw InputError(file, 0, "no Global_RFM element (not a DIMAP RPC file)");
  for (const char* name : kDimapRpcElements) {
    const auto& seen = rpc_elements[name];
    if (seen.size() > 1)
      throw InputError(file, std::next(seen.begin())->second, std::string("a second ") + name + " element (the first at line " +
                                                                  std::to_string(seen.begin()->second) +
                                                                  "): two models, and which is the image's is not guessed");
    if (!seen.empty()) break;  // the element the model is read from
  }
  const bool v1 = d.leaves.count(d.base + "Inverse_Model.F_COL") || d.leaves.count(d.base + "Inverse_Model.F_ROW");
  const RpcModel m = v1 ? dimap_v1_model(d) : dimap_v2_model(d);
  check_model(m, file);
  if (m.has_direct && (zero(m.lon_den) || zero(m.lat_den))) throw InputError(file, 0, "a Direct_Model denominator is all zeros");
  return m;
}

void xml_poly(std::ostringstream& os, const char* indent, const std::string& name, const RpcPoly& p) {
  for (int i = 0; i < 20; ++i)
    os << indent << '<' << name << '_' << i + 1 << '>' << format_number(p[i]) << "</" << name << '_' << i + 1 << ">\n";
}

// ---------------------------------------------------------------- OSSIM keyword list (.geom)

// "key: value" lines of an OSSIM keyword list (blank lines and // comments skipped; a value opened by
// """ runs to the next """, over lines if need be): key -> value, its line, the line of a second one.
struct KwlValue {
  std::string text;
  long line;
  long repeated_at = 0;
};
std::map<std::string, KwlValue> ossim_keywords(const std::string& text, const std::string& file) {
  std::map<std::string, KwlValue> out;
  std::istringstream in(text);
  std::string raw;
  long no = 0;
  while (std::getline(in, raw)) {
    const long at = ++no;
    const std::string t = trim(raw);
    if (t.empty() || t.rfind("//", 0) == 0) continue;
    const size_t colon = t.find(':');
    const std::string key = colon == std::string::npos ? std::string() : trim(t.substr(0, colon));
    if (key.empty()) throw InputError(file, at, "expected 'key: value'");
    std::string value = trim(t.substr(colon + 1));
    if (value.rfind("\"\"\"", 0) == 0) {
      while (value.find("\"\"\"", 3) == std::string::npos) {
        if (!std::getline(in, raw)) throw InputError(file, at, key + ": a \"\"\" value without its closing \"\"\"");
        ++no;
        value += "\n" + raw;
      }
    }
    auto [it, fresh] = out.emplace(key, KwlValue{value, at});
    if (!fresh && !it->second.repeated_at) it->second.repeated_at = at;
  }
  return out;
}

// The OSSIM models that keep their RPC in ossimRpcModel's keywords (ossimRpcModel::saveState): OSSIM's
// own and OTB's (ossimPleiadesModel, ossimSpot6Model).
const char* const kOssimRpcTypes[] = {"ossimRpcModel",          "ossimPleiadesModel",  "ossimSpot6Model",
                                      "ossimNitfRpcModel",      "ossimQuickbirdRpcModel", "ossimIkonosRpcModel"};

// RPC00A's term order 1 L P H LP LH PH LPH L2 P2 H2 L3 L2P L2H LP2 P3 P2H LH2 PH2 H3 (OSSIM's
// polynomial_format A): kRpc00aTerm[j] is the RPC00A index of RPC00B's term j.
const int kRpc00aTerm[20] = {0, 1, 2, 3, 4, 5, 6, 8, 9, 10, 7, 11, 14, 17, 12, 15, 18, 13, 16, 19};

// An OSSIM RPC keyword list: type, polynomial_format (B: RPC00B's term order; A: RPC00A's, reordered
// here), RPC00B's scalars under OSSIM's names (line_off .. height_scale, bias_error, rand_error) and
// line_num_coeff_00 .. _19, line_den_coeff_, samp_num_coeff_, samp_den_coeff_; every other key (OTB's
// support_data., adjustment_0., rect, ...) is ignored. OSSIM's image space has (0, 0) at the centre of
// the top-left pixel, as RPC00B (ossimNitfRpcModel takes the RPC00B offsets unchanged, its image rectangle
// 0 .. width - 1; OTB writes a Pléiades DIMAP SAMP_OFF of 20000.5 as samp_off 19999.5): taken as it is.
RpcModel parse_geom(const std::string& text, const std::string& file) {
  const auto kw = ossim_keywords(text, file);
  auto get = [&](const std::string& key, bool required) -> const KwlValue* {
    auto it = kw.find(key);
    if (it == kw.end()) {
      if (required) throw InputError(file, 0, "missing " + key);
      return nullptr;
    }
    if (it->second.repeated_at)
      throw InputError(file, it->second.repeated_at, key + " given twice (first at line " + std::to_string(it->second.line) + ")");
    return &it->second;
  };
  const KwlValue* type = get("type", true);
  if (std::find(std::begin(kOssimRpcTypes), std::end(kOssimRpcTypes), type->text) == std::end(kOssimRpcTypes))
    throw InputError(file, type->line, "type: " + type->text + " is not an OSSIM RPC model (ossimRpcModel, ossimPleiadesModel, ...)");
  // OTB's ossimPleiadesModel (and ossimSpot6Model) keeps an RPC only for SENSOR products
  if (const KwlValue* level = get("support_data.processing_level", false); level && level->text != "SENSOR")
    throw InputError(file, level->line, "a " + level->text + " product: its " + type->text + " carries no RPC (SENSOR products do)");
  const KwlValue* format = get("polynomial_format", true);
  if (format->text != "A" && format->text != "B")
    throw InputError(file, format->line, "polynomial_format: '" + format->text + "' (expected B, RPC00B, or A, RPC00A)");
  RpcModel m;
  for (const auto& f : kScalars)
    if (const KwlValue* v = get(f.geom, !optional_field(f))) m.*f.member = number_or_throw(v->text, file, v->line, f.geom);
  for (const auto& p : kPolys)
    for (int j = 0; j < 20; ++j) {  // RPC00B's term j: the file's term j (B) or kRpc00aTerm[j] (A)
      char key[32];
      std::snprintf(key, sizeof key, "%s_%02d", p.geom, format->text == "A" ? kRpc00aTerm[j] : j);
      const KwlValue* v = get(key, true);
      (m.*p.member)[j] = number_or_throw(v->text, file, v->line, key);
    }
  check_model(m, file);
  return m;
}

// ---------------------------------------------------------------- GDAL PAM .aux.xml

// The RPC metadata domain of a GDAL PAM file (<PAMDataset><Metadata domain="RPC"><MDI key="LINE_OFF">
// ...</MDI>...): the keys of GDAL's RPC metadata (those of _rpc.txt, each polynomial's 20 coefficients in
// one value; MIN_LONG .. MAX_LAT ignored). GDAL's RPC metadata is RPC00B's, (0, 0) at the centre of the
// top-left pixel (alg/gdal_rpc.cpp): taken as it is. Nothing when the file has no RPC domain (GDAL writes
// .aux.xml files for statistics and other metadata too).
std::optional<RpcModel> parse_aux(const std::string& text, const std::string& file) {
  std::map<std::string, XmlLeaf> md;
  xml_walk(text, file, [&](const std::vector<XmlOpen>& path, const std::string& value, long line) {
    if (path.size() != 3 || path[1].name != "Metadata" || path[2].name != "MDI") return;
    auto domain = path[1].attributes.find("domain");
    if (domain == path[1].attributes.end() || domain->second != "RPC") return;
    auto key = path[2].attributes.find("key");
    if (key == path[2].attributes.end() || key->second.empty())
      throw InputError(file, line, "an MDI element of the RPC domain without a key");
    auto [it, fresh] = md.emplace(key->second, XmlLeaf{value, line});
    if (!fresh)
      throw InputError(file, line, key->second + " given twice (first at line " + std::to_string(it->second.line) + ")");
  });
  if (md.empty()) return std::nullopt;
  auto get = [&](const char* key, bool required) -> const XmlLeaf* {
    auto it = md.find(key);
    if (it == md.end() && required) throw InputError(file, 0, std::string("missing ") + key + " in the RPC metadata domain");
    return it == md.end() ? nullptr : &it->second;
  };
  RpcModel m;
  for (const auto& f : kScalars)
    if (const XmlLeaf* v = get(f.txt, !optional_field(f))) m.*f.member = number_or_throw(v->text, file, v->line, f.txt);
  for (const auto& p : kPolys) {
    const XmlLeaf* v = get(p.txt, true);
    const std::vector<double> c = numbers_or_throw(v->text, file, v->line, p.txt, 20);
    std::copy(c.begin(), c.end(), (m.*p.member).begin());
  }
  check_model(m, file);
  return m;
}

}  // namespace

// ---------------------------------------------------------------- public

const char* rpc_form_name(RpcForm f) {
  switch (f) {
    case RpcForm::tiff: return "tiff";
    case RpcForm::nitf: return "nitf";
    case RpcForm::txt: return "txt";
    case RpcForm::rpb: return "rpb";
    case RpcForm::dimap: return "dimap";
    case RpcForm::geom: return "geom";
    case RpcForm::aux: return "aux";
  }
  return "?";
}

namespace {
std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// GDAL's PAM sidecar IMAGE.aux.xml ends with .xml too: it is told apart by its whole suffix
bool is_aux_xml(const std::string& path) {
  std::string name = fs::path(path).filename().string();
  for (auto& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name.size() > 8 && name.compare(name.size() - 8, 8, ".aux.xml") == 0;
}
}  // namespace

RpcForm rpc_form_of(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (is_aux_xml(path)) return RpcForm::aux;
  if (ext == ".geom") return RpcForm::geom;
  if (ext == ".rpb") return RpcForm::rpb;
  if (ext == ".txt") return RpcForm::txt;
  if (ext == ".xml") return RpcForm::dimap;
  if (ext == ".tif" || ext == ".tiff") return RpcForm::tiff;
  if (ext == ".ntf" || ext == ".nitf" || ext == ".nsf") return RpcForm::nitf;
  throw InputError(path, 0, "unknown RPC file kind (expected .RPB, _rpc.txt, RPC_*.XML, .geom, .aux.xml, a GeoTIFF or a NITF image)");
}

RpcModel read_rpc_txt(const std::string& path) { return parse_txt(read_whole(path), path); }
RpcModel read_rpc_rpb(const std::string& path) { return parse_rpb(read_whole(path), path); }
RpcModel read_rpc_dimap(const std::string& path) { return parse_dimap(read_whole(path), path); }
RpcModel read_rpc_geom(const std::string& path) { return parse_geom(read_whole(path), path); }
std::optional<RpcModel> read_rpc_aux(const std::string& path) { return parse_aux(read_whole(path), path); }

std::array<double, 92> rpc_tag_values(const RpcModel& m) {
  RpcTagValues v;
  for (int i = 0; i < 12; ++i) v[i] = m.*kScalars[i].member;
  for (int p = 0; p < 4; ++p)
    for (int i = 0; i < 20; ++i) v[12 + 20 * p + i] = (m.*kPolys[p].member)[i];
  return v;
}

RpcModel rpc_from_tag_values(const std::array<double, 92>& v) {
  RpcModel m;
  for (int i = 0; i < 12; ++i) m.*kScalars[i].member = v[i];
  for (int p = 0; p < 4; ++p)
    for (int i = 0; i < 20; ++i) (m.*kPolys[p].member)[i] = v[12 + 20 * p + i];
  return m;
}

std::optional<RpcModel> read_rpc_tiff(const std::string& path) {
  auto v = read_rpc_tag(path);
  if (!v) {
    // libtiff reads a tag whose values it cannot reach as no tag: that one is a damaged model, not none
    constexpr uint16_t kRpcTag = 50844;
    if (const auto e = tiff_first_ifd_tag(path, kRpcTag)) {
      std::error_code ec;
      const uintmax_t size = fs::file_size(path, ec);
      const bool past = !ec && e->bytes != 0 && (e->bytes > size || e->offset > size - e->bytes);
      throw InputError(path, 0, "RPC tag 50844 is corrupt: its " + std::to_string(e->count) + " values of TIFF type " +
                                    std::to_string(e->type) +
                                    (past ? " (" + std::to_string(e->bytes) + " bytes from byte " + std::to_string(e->offset) +
                                                ") run past the end of the file (" + std::to_string(size) + " bytes)"
                                          : std::string(" cannot be read")) +
                                    ": give the model with --rpc IMAGE=FILE");
    }
    return std::nullopt;
  }
  RpcModel m = rpc_from_tag_values(*v);
  check_model(m, path);
  return m;
}

std::optional<RpcModel> read_rpc_ntf(const std::string& path) {
  auto m = read_rpc_nitf(read_nitf_image(path));
  if (m) check_model(*m, path);
  return m;
}

RpcModel read_rpc_file(const std::string& path) {
  switch (rpc_form_of(path)) {
    case RpcForm::nitf: {
      auto m = read_rpc_ntf(path);
      if (!m) throw InputError(path, 0, "no RPC00B or RPC00A TRE in this NITF image");
      return *m;
    }
    case RpcForm::txt: return read_rpc_txt(path);
    case RpcForm::rpb: return read_rpc_rpb(path);
    case RpcForm::dimap: return read_rpc_dimap(path);
    case RpcForm::geom: return read_rpc_geom(path);
    case RpcForm::aux: {
      auto m = read_rpc_aux(path);
      if (!m) throw InputError(path, 0, "no RPC metadata domain (<Metadata domain=\"RPC\">) in this GDAL .aux.xml");
      return *m;
    }
    case RpcForm::tiff: {
      auto m = read_rpc_tiff(path);
      if (!m) throw InputError(path, 0, "no RPC tag 50844 in this TIFF");
      return *m;
    }
  }
  throw InputError(path, 0, "unknown RPC file kind");
}

std::string format_rpc_txt(const RpcModel& m) {
  std::ostringstream os;
  for (const auto& f : kScalars) os << f.txt << ": " << format_number(m.*f.member) << '\n';
  for (const auto& p : kPolys)
    for (int i = 0; i < 20; ++i) os << p.txt << '_' << i + 1 << ": " << format_number((m.*p.member)[i]) << '\n';
  return os.str();
}

std::string format_rpc_rpb(const RpcModel& m) {
  std::ostringstream os;
  os << "satId = \"tpkit\";\nbandId = \"P\";\nSpecId = \"RPC00B\";\nBEGIN_GROUP = IMAGE\n";
  for (const auto& f : kScalars) os << '\t' << f.rpb << " = " << format_number(m.*f.member) << ";\n";
  for (const auto& p : kPolys) os << '\t' << p.rpb << " = (\n\t\t\t" << join_poly(m.*p.member, ",\n\t\t\t") << ");\n";
  os << "END_GROUP = IMAGE\nEND;\n";
  return os.str();
}

std::string format_rpc_geom(const RpcModel& m) {
  // an ossimRpcModel keyword list, its keys sorted as OSSIM writes them; one "key: value" per line
  std::map<std::string, std::string> kw = {{"type", "ossimRpcModel"}, {"polynomial_format", "B"}};
  for (const auto& f : kScalars) kw[f.geom] = format_number(m.*f.member);
  for (const auto& p : kPolys)
    for (int i = 0; i < 20; ++i) {
      char key[32];
      std::snprintf(key, sizeof key, "%s_%02d", p.geom, i);
      kw[key] = format_number((m.*p.member)[i]);
    }
  std::ostringstream os;
  for (const auto& [key, value] : kw) os << key << ": " << value << '\n';
  return os.str();
}

std::string format_rpc_aux(const RpcModel& m) {
  // a PAM file holding GDAL's RPC metadata domain only, its keys sorted as GDAL writes them
  std::map<std::string, std::string> md;
  for (const auto& f : kScalars) md[f.txt] = format_number(m.*f.member);
  for (const auto& p : kPolys) md[p.txt] = join_poly(m.*p.member, " ");
  std::ostringstream os;
  os << "<PAMDataset>\n  <Metadata domain=\"RPC\">\n";
  for (const auto& [key, value] : md) os << "    <MDI key=\"" << key << "\">" << value << "</MDI>\n";
  os << "  </Metadata>\n</PAMDataset>\n";
  return os.str();
}

RpcModel with_direct_model(const RpcModel& m) {
  if (m.has_direct) return m;
  // the direct model is the RPC00B fit of (x, y, h) -> (lon, lat), with the roles of ground and image swapped
  RpcFitVolume v;
  v.lon0 = m.samp_off - m.samp_scale;
  v.lon1 = m.samp_off + m.samp_scale;
  v.lat0 = m.line_off - m.line_scale;
  v.lat1 = m.line_off + m.line_scale;
  v.h0 = m.height_off - m.height_scale;
  v.h1 = m.height_off + m.height_scale;
  RpcFit f = fit_rpc(
      [&](const Eigen::Vector3d& xyh) {
        try {
          Eigen::Vector2d ll = m.localize(xyh[0], xyh[1], xyh[2]);
          return ll;
        } catch (const NumericalError&) {
          return Eigen::Vector2d(NAN, NAN);
        }
      },
      v);
  RpcModel out = m;
  out.has_direct = true;
  // the fit normalizes its outputs by its own offsets and scales; re-express them with the model's
  // lon/lat normalization: lon = (N/D) * s_f + o_f = ((N * s_f + D * (o_f - o_m)) / s_m) / D * s_m + o_m
  auto renorm = [](const RpcPoly& num, const RpcPoly& den, double s_f, double o_f, double s_m, double o_m, RpcPoly& n_out,
                   RpcPoly& d_out) {
    for (int i = 0; i < 20; ++i) n_out[i] = (num[i] * s_f + den[i] * (o_f - o_m)) / s_m;
    d_out = den;
  };
  // the fit's "image" outputs are (lon, lat) as its samp and line
  renorm(f.model.samp_num, f.model.samp_den, f.model.samp_scale, f.model.samp_off, m.lon_scale, m.lon_off, out.lon_num,
         out.lon_den);
  renorm(f.model.line_num, f.model.line_den, f.model.line_scale, f.model.line_off, m.lat_scale, m.lat_off, out.lat_num,
         out.lat_den);
  // the fit's inputs were normalized by its own (x, y, h) box, which is the model's (samp, line, height) box
  return out;
}

std::string format_rpc_dimap(const RpcModel& model) {
  RpcModel m = with_direct_model(model);
  std::ostringstream os;
  os << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
        "<Dimap_Document name=\"RPC\">\n"
        "  <Metadata_Identification>\n"
        "    <METADATA_FORMAT version=\"2.0\">DIMAP</METADATA_FORMAT>\n"
        "    <METADATA_PROFILE>PHR_SENSOR</METADATA_PROFILE>\n"
        "    <METADATA_SUBPROFILE>RPC</METADATA_SUBPROFILE>\n"
        "  </Metadata_Identification>\n"
        "  <Rational_Function_Model>\n"
        "    <Global_RFM>\n"
        "      <Direct_Model>\n";
  const char* in = "        ";
  xml_poly(os, in, "SAMP_NUM_COEFF", m.lon_num);
  xml_poly(os, in, "SAMP_DEN_COEFF", m.lon_den);
  xml_poly(os, in, "LINE_NUM_COEFF", m.lat_num);
  xml_poly(os, in, "LINE_DEN_COEFF", m.lat_den);
  os << "      </Direct_Model>\n      <Inverse_Model>\n";
  for (const auto& p : kPolys) xml_poly(os, in, p.txt, m.*p.member);
  // validity domain: DIMAP pixels are 1-based
  os << "      </Inverse_Model>\n"
        "      <RFM_Validity>\n"
        "        <Direct_Model_Validity_Domain>\n"
        "          <FIRST_ROW>" << format_number(std::max(1.0, std::floor(m.line_off - m.line_scale) + 1)) << "</FIRST_ROW>\n"
        "          <FIRST_COL>" << format_number(std::max(1.0, std::floor(m.samp_off - m.samp_scale) + 1)) << "</FIRST_COL>\n"
        "          <LAST_ROW>" << format_number(std::ceil(m.line_off + m.line_scale) + 1) << "</LAST_ROW>\n"
        "          <LAST_COL>" << format_number(std::ceil(m.samp_off + m.samp_scale) + 1) << "</LAST_COL>\n"
        "        </Direct_Model_Validity_Domain>\n"
        "        <Inverse_Model_Validity_Domain>\n"
        "          <FIRST_LON>" << format_number(m.lon_off - m.lon_scale) << "</FIRST_LON>\n"
        "          <FIRST_LAT>" << format_number(m.lat_off - m.lat_scale) << "</FIRST_LAT>\n"
        "          <LAST_LON>" << format_number(m.lon_off + m.lon_scale) << "</LAST_LON>\n"
        "          <LAST_LAT>" << format_number(m.lat_off + m.lat_scale) << "</LAST_LAT>\n"
        "        </Inverse_Model_Validity_Domain>\n"
        "        <LONG_SCALE>" << format_number(m.lon_scale) << "</LONG_SCALE>\n"
        "        <LONG_OFF>" << format_number(m.lon_off) << "</LONG_OFF>\n"
        "        <LAT_SCALE>" << format_number(m.lat_scale) << "</LAT_SCALE>\n"
        "        <LAT_OFF>" << format_number(m.lat_off) << "</LAT_OFF>\n"
        "        <HEIGHT_SCALE>" << format_number(m.height_scale) << "</HEIGHT_SCALE>\n"
        "        <HEIGHT_OFF>" << format_number(m.height_off) << "</HEIGHT_OFF>\n"
        "        <SAMP_SCALE>" << format_number(m.samp_scale) << "</SAMP_SCALE>\n"
        "        <SAMP_OFF>" << dimap_offset(m.samp_off) << "</SAMP_OFF>\n"
        "        <LINE_SCALE>" << format_number(m.line_scale) << "</LINE_SCALE>\n"
        "        <LINE_OFF>" << dimap_offset(m.line_off) << "</LINE_OFF>\n"
        "      </RFM_Validity>\n"
        "    </Global_RFM>\n"
        "  </Rational_Function_Model>\n"
        "</Dimap_Document>\n";
  return os.str();
}

void write_rpc_txt(const std::string& path, const RpcModel& m) { write_file_atomic(path, format_rpc_txt(m)); }
void write_rpc_rpb(const std::string& path, const RpcModel& m) { write_file_atomic(path, format_rpc_rpb(m)); }
void write_rpc_dimap(const std::string& path, const RpcModel& m) { write_file_atomic(path, format_rpc_dimap(m)); }
void write_rpc_geom(const std::string& path, const RpcModel& m) { write_file_atomic(path, format_rpc_geom(m)); }
void write_rpc_aux(const std::string& path, const RpcModel& m) { write_file_atomic(path, format_rpc_aux(m)); }

void write_rpc_tiff_copy(const std::string& image, const std::string& out, const RpcModel& m) {
  copy_tiff_with_rpc_tag(image, out, rpc_tag_values(m));
}

void write_rpc_file(const std::string& path, RpcForm form, const RpcModel& m) {
  switch (form) {
    case RpcForm::txt: return write_rpc_txt(path, m);
    case RpcForm::rpb: return write_rpc_rpb(path, m);
    case RpcForm::dimap: return write_rpc_dimap(path, m);
    case RpcForm::geom: return write_rpc_geom(path, m);
    case RpcForm::aux: return write_rpc_aux(path, m);
    case RpcForm::tiff: throw UsageError("an RPC tag is written into a copy of an image (write_rpc_tiff_copy)");
    case RpcForm::nitf: throw UsageError("an RPC00B TRE is written with the image (tp-rpc crop -o IMAGE.ntf)");
  }
}

std::vector<std::string> rpc_sidecar_candidates(const std::string& image) {
  fs::path p(image);
  fs::path stem = p.parent_path() / p.stem();
  // GDAL's PAM file first: it is named after this very file (IMAGE.tif.aux.xml), and it is where GDAL
  // users set or correct a model (SetMetadata on a read-only image) while the vendor's sidecar stays as
  // delivered; then the sidecars named after the image's stem
  std::vector<std::string> out = {image + ".aux.xml",      stem.string() + "_rpc.txt", stem.string() + "_RPC.TXT",
                                  stem.string() + ".RPB",  stem.string() + ".rpb",     stem.string() + ".geom"};
  std::string name = p.stem().string();
  if (name.rfind("IMG_", 0) == 0) {
    // DIMAP products: v2 / v3 RPC_NAME.XML for IMG_NAME[_RiCj]; v1 one PHRDIMAP.XML beside the images
    // (IMG_R1C1.JP2, ...), where OTB's ossimPleiadesModel looks for it
    std::string rest = std::regex_replace(name.substr(4), std::regex("_R[0-9]+C[0-9]+$"), "");
    out.push_back((p.parent_path() / ("RPC_" + rest + ".XML")).string());
    out.push_back((p.parent_path() / "PHRDIMAP.XML").string());
  }
  return out;
}

std::optional<RpcSource> find_image_rpc(const std::string& image, const std::map<std::string, std::string>& overrides) {
  const auto it = overrides.find(image);
  if (it != overrides.end()) return RpcSource{read_rpc_file(it->second), it->second, rpc_form_of(it->second)};
  std::string ext = fs::path(image).extension().string();
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".tif" || ext == ".tiff") {
    if (auto m = read_rpc_tiff(image)) return RpcSource{*m, image, RpcForm::tiff};
  } else if (is_nitf_file(image)) {
    if (auto m = read_rpc_ntf(image)) return RpcSource{*m, image, RpcForm::nitf};
  }
  for (const auto& c : rpc_sidecar_candidates(image)) {
    if (!fs::is_regular_file(c)) continue;
    const RpcForm form = rpc_form_of(c);
    if (form == RpcForm::dimap) {
      // a DIMAP product's model is the whole image's, whose top-left pixel is tile R1C1's: any other tile
      // would get the whole image's pixels (GDAL shifts it by the tile layout of the DIM file, not read here)
      std::smatch t;
      const std::string stem = fs::path(image).stem().string();
      if (std::regex_search(stem, t, std::regex("_R([0-9]+)C([0-9]+)$")) && (std::stoi(t[1]) != 1 || std::stoi(t[2]) != 1))
        throw InputError(image, 0, "tile R" + t[1].str() + "C" + t[2].str() + " of a DIMAP product: " + fs::path(c).filename().string() +
                                       " is the model of the whole image (tile R1C1's pixels), and the tile's offset in it is not known "
                                       "here: mosaic the tiles, or give --rpc IMAGE=FILE with the model shifted to the tile");
    }
    if (form != RpcForm::aux) return RpcSource{read_rpc_file(c), c, form};
    // GDAL writes .aux.xml files for statistics and other metadata too: one without an RPC domain is passed
    if (auto m = read_rpc_aux(c)) return RpcSource{*m, c, form};
  }
  return std::nullopt;
}

RpcSource load_image_rpc(const std::string& image, const std::map<std::string, std::string>& overrides) {
  if (auto s = find_image_rpc(image, overrides)) return *s;
  std::string names;
  for (const auto& c : rpc_sidecar_candidates(image)) names += (names.empty() ? "" : ", ") + fs::path(c).filename().string();
  const char* inside = is_nitf_file(image) ? "no RPC00B or RPC00A TRE" : "no tag 50844";
  throw InputError(image, 0, std::string("no RPC model: ") + inside + ", none of " + names + " beside it, and no --rpc " + image + "=FILE");
}

RpcSource load_rpc_model(const std::string& image_or_model) {
  const std::string ext = lower_extension(image_or_model);
  if (ext == ".rpb" || ext == ".txt" || ext == ".xml" || ext == ".geom") {
    const RpcForm form = rpc_form_of(image_or_model);
    return {read_rpc_file(image_or_model), image_or_model, form};
  }
  return load_image_rpc(image_or_model);
}

std::map<std::string, std::string> parse_rpc_overrides(const std::vector<std::string>& values) {
  std::map<std::string, std::string> out;
  for (const auto& v : values) {
    size_t eq = v.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == v.size())
      throw UsageError("--rpc: expected IMAGE=FILE, got '" + v + "'");
    if (!out.emplace(v.substr(0, eq), v.substr(eq + 1)).second)
      throw UsageError("--rpc: image '" + v.substr(0, eq) + "' given twice");
  }
  return out;
}

int image_index(const std::string& ref, const std::vector<std::string>& images, const std::string& listed_in) {
  for (size_t i = 0; i < images.size(); ++i)
    if (images[i] == ref) return static_cast<int>(i);
  std::error_code ec;
  const fs::path base = fs::path(listed_in).parent_path();
  for (const fs::path& cand : {fs::path(ref), base / ref})
    if (fs::exists(cand, ec))
      for (size_t i = 0; i < images.size(); ++i)
        if (fs::exists(images[i], ec) && fs::equivalent(cand, images[i], ec)) return static_cast<int>(i);
  int found = -1;
  for (size_t i = 0; i < images.size(); ++i)
    if (fs::path(images[i]).filename() == fs::path(ref).filename()) {
      if (found >= 0) return -2;  // ambiguous
      found = static_cast<int>(i);
    }
  return found;
}

std::map<std::string, std::string> resolve_rpc_overrides(const std::map<std::string, std::string>& overrides,
                                                         const std::vector<std::string>& images) {
  std::map<std::string, std::string> out;
  for (const auto& [image, file] : overrides) {
    const int i = image_index(image, images);
    if (i < 0)
      throw UsageError("--rpc " + image + "=" + file + ": " + image + " is " + (i == -2 ? "ambiguous among" : "not one of") + " the images");
    if (!out.emplace(images[static_cast<size_t>(i)], file).second)
      throw UsageError("--rpc " + image + "=" + file + ": " + images[static_cast<size_t>(i)] + " has another --rpc already");
  }
  return out;
}

}  // namespace tpkit
