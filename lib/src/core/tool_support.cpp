#include "tpkit/core/tool_support.hpp"

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <sstream>
#include <vector>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/version.hpp"

namespace tpkit {

namespace {
std::string g_tool = "tpkit";
std::vector<std::string> g_summaries;  // summary(): printed after the commit
std::mutex g_summary_mutex;

// One line of a message, whatever the message holds (CLI11 joins some with line breaks).
std::string one_line(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '\n' || c == '\r') {
      while (!out.empty() && out.back() == ' ') out.pop_back();
      if (!out.empty() && out.back() != ';' && out.back() != ':') out += ';';
      out += ' ';
    } else {
      out += c;
    }
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == ';')) out.pop_back();
  return out;
}

std::string strip_fonts(std::string s) {
  // \fB \fI \fR \fP font changes, \- and \(em escapes, \e backslash, \[uXXXX] and \['e] characters
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\\' && i + 1 < s.size()) {
      char c = s[i + 1];
      const size_t close = c == '[' ? s.find(']', i + 2) : std::string::npos;
      if (close != std::string::npos) {
        const std::string name = s.substr(i + 2, close - i - 2);
        char* end = nullptr;
        const unsigned long cp = name.size() > 1 && name[0] == 'u' ? std::strtoul(name.c_str() + 1, &end, 16) : 0;
        if (cp > 0 && end && *end == '\0' && cp < 0x10000) {  // UTF-8 of a code point of the basic plane
          if (cp < 0x80) out += static_cast<char>(cp);
          else if (cp < 0x800) out += static_cast<char>(0xC0 | (cp >> 6)), out += static_cast<char>(0x80 | (cp & 0x3F));
          else
            out += static_cast<char>(0xE0 | (cp >> 12)), out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F)),
                out += static_cast<char>(0x80 | (cp & 0x3F));
        } else if (name == "'e") {
          out += "\u00e9";
        } else {
          out += name;
        }
        i = close;
        continue;
      }
      if (c == 'f' && i + 2 < s.size()) {
        i += 2;
        continue;
      }
      if (c == '-') { out += '-'; ++i; continue; }
      if (c == 'e') { out += '\\'; ++i; continue; }
      if (c == '&') { ++i; continue; }
      if (c == ' ') { out += ' '; ++i; continue; }
      if (c == '(' && i + 3 < s.size()) {
        std::string code = s.substr(i + 2, 2);
        if (code == "em") out += "--";
        else if (code == "mu") out += "x";
        else if (code == "bu") out += "*";
        else if (code == "aq") out += "'";
        else if (code == "dq") out += "\"";
        else if (code == "+-") out += "+-";
        else if (code == "*b") out += "β";
        else if (code == "*a") out += "α";
        else if (code == "*g") out += "γ";
        else if (code == "*r") out += "ρ";
        else if (code == "*s") out += "σ";
        else if (code == "*h") out += "θ";
        else if (code == "<=") out += "<=";
        else if (code == ">=") out += ">=";
        else out += code;
        i += 3;
        continue;
      }
    }
    out += s[i];
  }
  return out;
}

// Alternating-font macros (.BR a b c) join their words without spaces; quotes group words.
std::string join_alternating(const std::string& args) {
  std::string out, word;
  bool q = false;
  for (char c : args) {
    if (c == '"') { q = !q; continue; }
    if (c == ' ' && !q) {
      out += word;
      word.clear();
      continue;
    }
    word += c;
  }
  return out + word;
}

std::string unquote(const std::string& s) {
  std::string out;
  for (char c : s)
    if (c != '"') out += c;
  return out;
}
}  // namespace

namespace {
CLI::Validator number_check(bool allow_zero) {
  return CLI::Validator(
      [allow_zero](std::string& v) -> std::string {
        char* end = nullptr;
        const double d = std::strtod(v.c_str(), &end);
        if (end == v.c_str() || *end != '\0') return "not a number: '" + v + "'";
        if (allow_zero ? !(d >= 0) : !(d > 0)) return std::string(allow_zero ? "must be >= 0" : "must be > 0") + ", got '" + v + "'";
        return std::string();
      },
      allow_zero ? "NONNEGATIVE" : "POSITIVE");
}
}  // namespace

const CLI::Validator Positive = number_check(false);
const CLI::Validator NonNegative = number_check(true);

std::function<bool(const CLI::results_t&)> auto_or_pixels(std::optional<double>& target, const std::string& name, double lo, double hi) {
  return [&target, name, lo, hi](const CLI::results_t& r) {
    if (r[0] == "auto") {
      target.reset();
      return true;
    }
    size_t used = 0;
    double v = 0;
    try {
      v = std::stod(r[0], &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != r[0].size() || !std::isfinite(v) || v < lo || v > hi)
      throw CLI::ValidationError(name, "auto or a number of pixels in [" + format_number(lo) + ", " + format_number(hi) +
                                           "], got '" + r[0] + "'");
    target = v;
    return true;
  };
}

const std::string& tool_name() { return g_tool; }

std::string written_by() { return g_tool + ' ' + version_full(); }

void warn(const std::string& message) { std::cerr << g_tool << ": warning: " << message << std::endl; }

void summary(const std::string& line) {
  std::lock_guard<std::mutex> lock(g_summary_mutex);
  g_summaries.push_back(line);
}

std::string render_man_page(const char* roff) {
  std::istringstream in(roff ? roff : "");
  std::ostringstream out;
  std::string line;
  int indent = 7;
  int rs = 0;
  bool nofill = false;
  bool tp_pending = false;
  std::string para;
  auto flush = [&]() {
    if (para.empty()) return;
    // wrap at 100 columns
    std::istringstream ws(para);
    std::string w, cur;
    int ind = indent + rs;
    while (ws >> w) {
      if (!cur.empty() && static_cast<int>(cur.size() + 1 + w.size()) + ind > 100) {
        out << std::string(ind, ' ') << cur << '\n';
        cur.clear();
      }
      cur += (cur.empty() ? "" : " ") + w;
    }
    if (!cur.empty()) out << std::string(ind, ' ') << cur << '\n';
    para.clear();
  };
  while (std::getline(in, line)) {
    if (line.rfind(".\\\"", 0) == 0 || line.rfind("'\\\"", 0) == 0) continue;  // comment
    if (!line.empty() && line[0] == '.') {
      std::string mac = line.substr(1, line.find(' ') == std::string::npos ? std::string::npos : line.find(' ') - 1);
      std::string args = line.find(' ') == std::string::npos ? "" : line.substr(line.find(' ') + 1);
      if (mac == "TH") {
        std::istringstream a(args);
        std::string name, sec;
        a >> name >> sec;
        out << name << "(" << sec << ")\n";
      } else if (mac == "SH" || mac == "SS") {
        flush();
        out << '\n' << (mac == "SS" ? "   " : "") << strip_fonts(unquote(args)) << '\n';
        indent = 7;
      } else if (mac == "PP" || mac == "P" || mac == "LP") {
        flush();
        out << '\n';
        indent = 7;
      } else if (mac == "TP" || mac == "IP") {
        flush();
        out << '\n';
        indent = 7;
        if (mac == "TP") tp_pending = true;
        else if (!args.empty()) {
          // .IP TAG [WIDTH]: the tag is the first (possibly quoted) argument
          std::string tag;
          if (args[0] == '"') tag = args.substr(1, args.find('"', 1) - 1);
          else tag = args.substr(0, args.find(' '));
          tag = strip_fonts(tag);
          if (tag.size() <= 3) {
            para = tag;  // a bullet: the paragraph continues on the same line
            indent = 9;
          } else {
            out << std::string(7 + rs, ' ') << tag << '\n';
            indent = 11;
          }
        } else indent = 11;
      } else if (mac == "B" || mac == "I") {
        para += (para.empty() ? "" : " ") + strip_fonts(unquote(args));
      } else if (mac == "BR" || mac == "IR" || mac == "RB" || mac == "BI" || mac == "IB" || mac == "RI") {
        para += (para.empty() ? "" : " ") + strip_fonts(join_alternating(args));
      } else if (mac == "RS") {
        flush();
        rs += 4;
      } else if (mac == "RE") {
        flush();
        rs = rs >= 4 ? rs - 4 : 0;
      } else if (mac == "nf" || mac == "EX") {
        flush();
        nofill = true;
      } else if (mac == "fi" || mac == "EE") {
        nofill = false;
      } else if (mac == "br" || mac == "sp") {
        flush();
        if (mac == "sp") out << '\n';
      }
      if (tp_pending && (mac == "B" || mac == "I" || mac == "BR" || mac == "IR" || mac == "BI" || mac == "RB")) {
        out << std::string(7 + rs, ' ') << para << '\n';
        para.clear();
        indent = 11;
        tp_pending = false;
      }
      continue;
    }
    if (nofill) {
      out << std::string(indent + rs, ' ') << strip_fonts(line) << '\n';
      continue;
    }
    if (tp_pending) {
      out << std::string(7 + rs, ' ') << strip_fonts(line) << '\n';
      indent = 11;
      tp_pending = false;
      continue;
    }
    if (line.empty()) {
      flush();
      out << '\n';
      continue;
    }
    para += (para.empty() ? "" : " ") + strip_fonts(line);
  }
  flush();
  return out.str();
}

namespace {
class ManFormatter : public CLI::Formatter {
 public:
  explicit ManFormatter(std::string text) : text_(std::move(text)) {}
  std::string make_help(const CLI::App*, std::string, CLI::AppFormatMode) const override { return text_; }

 private:
  std::string text_;
};

// Every option's long names must appear in the page (as "--name", after escapes are removed).
std::string undocumented_options(const CLI::App& app, const std::string& page) {
  std::string missing;
  for (const CLI::Option* o : app.get_options()) {
    for (const auto& ln : o->get_lnames()) {
      if (ln == "help" || ln == "version") continue;
      if (page.find("--" + ln) == std::string::npos) missing += " --" + ln;
    }
    for (const auto& sn : o->get_snames()) {
      if (sn == "h") continue;
      std::string s = "-" + sn;
      if (page.find(s + " ") == std::string::npos && page.find(s + ",") == std::string::npos &&
          page.find(s + "\n") == std::string::npos)
        missing += " -" + sn;
    }
  }
  return missing;
}

// Every option that takes a fixed number of values (--height-range LO HI, --region X0 Y0 W H, ...) takes
// exactly that many: CLI11 lets a vector option go on taking the arguments that follow, so that
// `--height-range 0 100 IMG1 IMG2` swallowed the images and failed with "At Most 2 required but received 4".
// Its values are checked as they are parsed: one number short, `--region 0 0 100 IMG1 IMG2` took IMG1 for
// H, and the error reported was the images' count ("IMAGES: At least 2 required"), not the option's.
void fix_value_counts(CLI::App& app) {
  for (CLI::Option* opt : app.get_options()) {
    const int lo = opt->get_items_expected_min(), hi = opt->get_items_expected_max();
    if (lo == hi && hi > 1) opt->allow_extra_args(false)->trigger_on_parse();
  }
}

// Checks added to every option of a number type, whatever the tool declared: floating-point options
// take finite numbers only (NaN passes every `x < limit` check and would be written into headers; Inf is
// never a meaningful size, threshold or level); unsigned ones (seeds, counts) refuse a negative value,
// which CLI11 would wrap around.
void guard_number_options(CLI::App& app) {
  for (CLI::Option* opt : app.get_options()) {
    if (opt->get_type_name().find("FLOAT") == std::string::npos) continue;
    opt->check(CLI::Validator(
        [](std::string& v) -> std::string {
          char* end = nullptr;
          const double d = std::strtod(v.c_str(), &end);
          if (end != v.c_str() && !std::isfinite(d)) return "must be a finite number, got '" + v + "'";
          return std::string();
        },
        "", "finite"));
  }
  for (CLI::Option* opt : app.get_options()) {
    if (opt->get_type_name() != "UINT") continue;
    opt->check(CLI::Validator(
        [](std::string& v) -> std::string {
          return v.find('-') != std::string::npos ? "must be a non-negative integer, got '" + v + "'" : std::string();
        },
        "", "unsigned"));
  }
}

}  // namespace

int run_tool(const std::string& tool, int argc, char** argv, const ToolSetup& setup, const char* man_page) {
  g_tool = tool;
  std::string text = render_man_page(man_page);
  try {
    CLI::App app(tool, tool);
    app.formatter(std::make_shared<ManFormatter>(text));
    app.set_help_flag("-h,--help", "print the manual page and exit");
    app.set_version_flag("--version", tool + " (tpkit) " + version_full(), "print the version and exit");
    auto body = setup(app);
    guard_number_options(app);
    fix_value_counts(app);
    try {
      app.parse(argc, argv);
    } catch (const CLI::CallForHelp&) {
      const char* chk = std::getenv("TPKIT_CHECK_HELP");
      if (chk && std::string(chk) == "1") {
        std::string missing = undocumented_options(app, text);
        if (!missing.empty()) {
          std::cerr << tool << ": options missing from the man page:" << missing << "\n";
          return 2;
        }
      }
      std::cout << text;
      return 0;
    } catch (const CLI::CallForVersion& e) {
      std::cout << e.what() << "\n";
      return 0;
    } catch (const CLI::ParseError& e) {
      std::cerr << tool << ": " << one_line(e.what()) << " (see " << tool << " --help)\n";
      return 2;
    }
    // the body's outputs commit together when it succeeds, and are all discarded when it fails
    install_output_signal_cleanup();
    begin_outputs();
    struct Abort {
      ~Abort() { abort_outputs(); }  // no-op after commit_outputs()
    } abort_unless_committed;
    {
      std::lock_guard<std::mutex> lock(g_summary_mutex);
      g_summaries.clear();
    }
    const int rc = body();
    if (rc == 0 || rc == kExitNoAnswer) {
      commit_outputs();
      std::lock_guard<std::mutex> lock(g_summary_mutex);
      for (const auto& line : g_summaries) std::cerr << tool << ": " << line << "\n";
      g_summaries.clear();
    }
    return rc;
  } catch (const UsageError& e) {
    std::cerr << tool << ": " << one_line(e.what()) << "\n";
    return 2;
  } catch (const InputError& e) {
    std::cerr << tool << ": " << one_line(e.what()) << "\n";
    return 1;
  } catch (const NumericalError& e) {
    std::cerr << tool << ": " << one_line(e.what()) << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << tool << ": out of memory\n";
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {  // a folder made, a size asked for, a folder walked
    std::cerr << tool << ": " << one_line(filesystem_error_message(e)) << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << tool << ": " << one_line(e.what()) << "\n";
    return 1;
  }
}

struct Progress::Impl {
  std::string label;
  long total;
  std::atomic<long> count{0};
  std::mutex m;
  int last_pct = -1;
  bool tty;
  bool finished = false;
};

Progress::Progress(std::string label, long total) : impl_(new Impl) {
  impl_->label = std::move(label);
  impl_->total = total > 0 ? total : 1;
  impl_->tty = ::isatty(2);
}

Progress::~Progress() {
  done();
  delete impl_;
}

void Progress::add(long n) {
  long c = impl_->count += n;
  if (!impl_->tty) return;
  int pct = static_cast<int>(100 * std::min(c, impl_->total) / impl_->total);
  std::lock_guard<std::mutex> lock(impl_->m);
  if (pct == impl_->last_pct || impl_->finished) return;
  impl_->last_pct = pct;
  int w = 30, f = pct * w / 100;
  std::cerr << '\r' << g_tool << ": " << impl_->label << " [" << std::string(f, '#') << std::string(w - f, '.') << "] "
            << pct << "%" << std::flush;
}

void Progress::done() {
  std::lock_guard<std::mutex> lock(impl_->m);
  if (impl_->finished) return;
  impl_->finished = true;
  if (impl_->tty && impl_->last_pct >= 0) std::cerr << "\r\033[K" << std::flush;
}

}  // namespace tpkit
