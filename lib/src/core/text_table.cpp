#include "tpkit/core/text_table.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/version.hpp"

namespace tpkit {

std::string meta_get(const Meta& meta, const std::string& key) {
  for (const auto& kv : meta)
    if (kv.first == key) return kv.second;
  return "";
}

void meta_set(Meta& meta, const std::string& key, const std::string& value) {
  for (auto& kv : meta)
    if (kv.first == key) {
      kv.second = value;
      return;
    }
  meta.emplace_back(key, value);
}

int TextTable::find(const std::string& name) const {
  for (size_t i = 0; i < columns.size(); ++i)
    if (columns[i] == name) return static_cast<int>(i);
  return -1;
}

int TextTable::require(const std::string& name) const {
  int i = find(name);
  if (i < 0) throw InputError(source, 0, "missing column '" + name + "'");
  return i;
}

std::vector<double> TextTable::column(const std::string& name) const {
  int c = require(name);
  std::vector<double> v;
  v.reserve(rows.size());
  for (const auto& r : rows) v.push_back(r[c]);
  return v;
}

namespace {

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// The words of s between white space (the C locale's: space, \t \n \v \f \r), as `is >> word` reads them
// (without a stream per line: the records of a large file are read a million at a time).
void split_ws(const std::string& s, std::vector<std::string>& out) {
  auto space = [](char c) { return c == ' ' || (c >= '\t' && c <= '\r'); };
  size_t n = 0;
  const size_t len = s.size();
  for (size_t b = 0;;) {
    while (b < len && space(s[b])) ++b;
    if (b == len) break;
    size_t e = b;
    while (e < len && !space(s[e])) ++e;
    if (n == out.size()) out.emplace_back();
    out[n++].assign(s, b, e - b);
    b = e;
  }
  out.resize(n);
}

std::vector<std::string> split_ws(const std::string& s) {
  std::vector<std::string> out;
  split_ws(s, out);
  return out;
}

bool parse_double(const std::string& s, double& v) {
  const char* b = s.data();
  const char* e = b + s.size();
  if (b != e && *b == '+') ++b;  // from_chars does not take a leading '+'
  auto r = std::from_chars(b, e, v);
  return r.ec == std::errc() && r.ptr == e;
}

bool parse_long(const std::string& s, long& v) {
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

}  // namespace

TextTable read_table(std::istream& in, const std::string& source_in, const ReadOptions& given) {
  ReadOptions opt = given;  // with of_kind: replaced by the options of the header's kind
  TextTable t;
  t.source = source_in == "-" ? "<stdin>" : source_in;
  std::string line;
  long lineno = 0;
  bool header_seen = false;
  bool first_content = true;
  std::vector<std::string> f;  // a record's fields (reused)
  while (read_text_line(in, line, t.source, lineno + 1)) {
    ++lineno;
    if (lineno == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);  // a UTF-8 byte order mark
    std::string s = trim(line);
    if (s.empty()) continue;
    if (s[0] == '#') {
      std::string c = trim(s.substr(1));
      if (first_content) {
        first_content = false;
        auto w = split_ws(c);
        if (w.size() >= 1 && w[0] == "tpkit") {
          if (w.size() != 3) throw InputError(t.source, lineno, "malformed header; expected '# tpkit KIND VERSION'");
          long ver = 0;
          if (!parse_long(w[2], ver) || ver < 1) throw InputError(t.source, lineno, "bad version '" + w[2] + "' in header");
          if (opt.kind.empty() && opt.of_kind) opt = opt.of_kind(w[1]);
          if (!opt.kind.empty() && w[1] != opt.kind)
            throw InputError(t.source, lineno, "wrong header kind: expected '" + opt.kind + "', found '" + w[1] + "'");
          if (ver > opt.max_version)
            throw InputError(t.source, lineno, "version " + w[2] + " of '" + w[1] + "' is newer than this reader (" +
                                                   std::to_string(opt.max_version) + ")");
          t.kind = w[1];
          t.version = static_cast<int>(ver);
          header_seen = true;
          continue;
        }
      }
      {
        // a header anywhere but on the first line: a comment above it, or two files concatenated
        auto w = split_ws(c);
        long v = 0;
        if (w.size() == 3 && w[0] == "tpkit" && parse_long(w[2], v))
          throw InputError(t.source, lineno, header_seen ? "a second '# tpkit KIND VERSION' header (files concatenated?)"
                                                         : "the '# tpkit KIND VERSION' header must be the first line");
      }
      size_t colon = c.find(':');
      if (colon == std::string::npos || colon == 0 || c.find(' ') < colon) {
        if (!t.rows.empty() || !opt.columnar) t.interleaved_comments.emplace_back(t.rows.size(), c);
        continue;  // free comment
      }
      std::string key = c.substr(0, colon);
      std::string val = trim(c.substr(colon + 1));
      if (key == "columns") {
        if (!t.rows.empty()) throw InputError(t.source, lineno, "'# columns:' after the first record");
        t.columns = split_ws(val);
        if (t.columns.empty()) throw InputError(t.source, lineno, "empty '# columns:' line");
        for (size_t i = 0; i < t.columns.size(); ++i)
          for (size_t j = 0; j < i; ++j)
            if (t.columns[i] == t.columns[j]) throw InputError(t.source, lineno, "column '" + t.columns[i] + "' named twice");
      } else if (key.size() > 5 && key.compare(0, 5, "image") == 0 &&
                 key.find_first_not_of("0123456789", 5) == std::string::npos) {
        long n = 0;
        if (!parse_long(key.substr(5), n) || n < 1 || n > 1000) throw InputError(t.source, lineno, "bad image number in '" + key + "'");
        auto w = split_ws(val);
        if (w.empty()) throw InputError(t.source, lineno, "'# " + key + ":' names no image");
        ImageRef ref;
        ref.path = val;
        if (w.size() >= 3 && parse_long(w[w.size() - 2], ref.width) && parse_long(w[w.size() - 1], ref.height)) {
          // PATH WIDTH HEIGHT; the path may contain spaces: cut the last two words off the end
          std::string rest = val;
          for (int k = 0; k < 2; ++k) rest = trim(rest.substr(0, rest.find_last_of(" \t")));
          ref.path = rest;
        } else {
          ref.width = ref.height = 0;
        }
        if (static_cast<long>(t.images.size()) < n) t.images.resize(n);
        t.images[n - 1] = ref;
      } else if (key == "written-by") {
        t.written_by = val;  // not metadata: a file written from this one names its own writer
      } else {
        t.meta.emplace_back(key, val);
      }
      continue;
    }
    // a record
    first_content = false;
    split_ws(s, f);
    if (opt.columnar && t.columns.empty()) {
      if (header_seen || !opt.default_columns)
        throw InputError(t.source, lineno, "record before any '# columns:' line");
      t.columns = opt.default_columns(f.size());
      if (t.columns.empty())
        throw InputError(t.source, lineno, "headerless input with " + std::to_string(f.size()) +
                                               " fields does not fit the default columns of '" + opt.kind + "'");
    }
    if (opt.columnar && f.size() != t.columns.size()) {
      if (f.size() < t.columns.size())
        throw InputError(t.source, lineno, "missing column '" + t.columns[f.size()] + "' (" + std::to_string(f.size()) +
                                               " fields, " + std::to_string(t.columns.size()) + " columns)");
      throw InputError(t.source, lineno, "extra field '" + f[t.columns.size()] + "' (" + std::to_string(f.size()) +
                                             " fields, " + std::to_string(t.columns.size()) + " columns)");
    }
    std::vector<double> row(f.size());
    for (size_t i = 0; i < f.size(); ++i) {
      double v;
      auto name = [&] { return opt.columnar ? "'" + t.columns[i] + "'" : std::to_string(i + 1); };
      if (!parse_double(f[i], v)) throw InputError(t.source, lineno, "field " + name() + " is not a number: '" + f[i] + "'");
      if (!std::isfinite(v)) {
        const std::string column = i < t.columns.size() ? t.columns[i] : std::string();  // a row longer than its columns: ""
        if (!(std::isnan(v) && opt.may_be_missing && opt.may_be_missing(column)))
          throw InputError(t.source, lineno, "field " + name() + " is not finite: '" + f[i] + "'");
      }
      row[i] = v;
    }
    t.rows.push_back(std::move(row));
    t.row_line.push_back(lineno);
  }
  if (in.bad()) throw InputError(t.source, lineno, std::string("read error: ") + std::strerror(errno));
  // nothing at all (a closed or empty pipe, an empty file) is no table: a header with no records is
  if (first_content) throw InputError(t.source, 0, "empty input: no header and no records");
  if (opt.columnar && t.columns.empty() && opt.default_columns) t.columns = opt.default_columns(0);
  return t;
}

TextTable read_table_file(const std::string& path, const ReadOptions& opt) {
  if (path == "-") return read_table(std::cin, "-", opt);
  std::ifstream f = open_input_file(path, InputKind::stream, true);
  return read_table(f, path, opt);
}

namespace {
// Room for one number as put_number writes it: the shortest round-trip form of a double is at most 24
// characters ("-2.2250738585072014e-308").
constexpr size_t kNumberChars = 32;
// v as format_number writes it, at p (kNumberChars of room); returns the end
char* put_number(char* p, double v) {
  if (v == 0) {  // also folds -0
    *p = '0';
    return p + 1;
  }
  return std::to_chars(p, p + kNumberChars, v).ptr;
}
}  // namespace

std::string format_number(double v) {
  char buf[kNumberChars];
  return std::string(buf, put_number(buf, v));
}

std::string format_figure(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string format_id(double v) {
  if (std::floor(v) == v && std::fabs(v) < 9e15) {
    char buf[32];
    auto r = std::to_chars(buf, buf + sizeof buf, static_cast<long long>(v));
    return std::string(buf, r.ptr);
  }
  return format_number(v);
}

void write_header(std::ostream& os, const std::string& kind, int version, const std::vector<ImageRef>& images,
                  const Meta& meta, const std::vector<std::string>& columns) {
  os << "# tpkit " << kind << ' ' << version << '\n';
  os << "# written-by: " << written_by() << '\n';
  for (size_t i = 0; i < images.size(); ++i) {
    os << "# image" << (i + 1) << ": " << images[i].path;
    if (images[i].width > 0 || images[i].height > 0) os << ' ' << images[i].width << ' ' << images[i].height;
    os << '\n';
  }
  for (const auto& kv : meta) os << "# " << kv.first << ": " << kv.second << '\n';
  if (!columns.empty()) {
    os << "# columns:";
    for (const auto& c : columns) os << ' ' << c;
    os << '\n';
  }
}

// The record's line is made in a buffer and written at once, not a string and two stream insertions a
// number: the 10000² pair's 1.1 million matches (11 numbers each) are written in 0.56-0.71 s instead of
// 0.80-0.95 s, the same bytes; to_chars itself is most of what is left.
void write_record(std::ostream& os, const std::vector<double>& values) {
  char local[64 * (kNumberChars + 1)];
  std::unique_ptr<char[]> wide;
  char* line = local;
  if (values.size() > 64) {  // a track of many views
    wide.reset(new char[values.size() * (kNumberChars + 1)]);
    line = wide.get();
  }
  char* p = line;
  for (size_t i = 0; i < values.size(); ++i) {
    if (i) *p++ = ' ';
    p = put_number(p, values[i]);
  }
  *p++ = '\n';
  os.write(line, p - line);
}

}  // namespace tpkit
