// What every tpkit tool's main() shares: --help from the embedded man page, one catch of every error
// as "tool: file:line: reason", the exit codes (0 success, 1 bad input, 2 usage) and the progress bar.
//
//   extern const char* const tpkit_man_page;   // generated from man/TOOL.1 by the build
//   int main(int argc, char** argv) {
//     return tpkit::run_tool("tp-foo", argc, argv, [&](CLI::App& app) {
//       ... app.add_option(...) ...
//       return [&]() { ... library calls, writes ...; return 0; };   // runs after parsing
//     });
//   }
#pragma once
#include <CLI/CLI.hpp>
#include <functional>
#include <optional>
#include <string>

namespace tpkit {

// Option checks with short messages ("must be > 0, got '-1'"); CLI11's own PositiveNumber and
// NonNegativeNumber print the largest double in full.
extern const CLI::Validator Positive;
extern const CLI::Validator NonNegative;

// CLI11 callback of an option that takes `auto` (target unset) or a number of pixels in [lo, hi].
std::function<bool(const CLI::results_t&)> auto_or_pixels(std::optional<double>& target, const std::string& name, double lo, double hi);

// Exit code of a run that finished but has no answer it can stand behind (cluster-homog's rejected
// verdict): its outputs, if it wrote any (marked as such), are committed like those of a success.
constexpr int kExitNoAnswer = 3;

// Called with the app to declare options; returns the body to run once the command line is parsed.
using ToolSetup = std::function<std::function<int()>(CLI::App&)>;

// Parses the command line and runs the body. -h/--help prints the man page as text, --version the tool's
// name and tpkit's version (version.hpp); both exit 0 before any other option is checked. A usage error
// (CLI11's or the body's UsageError) is one line naming the option, exit 2. With the
// environment variable TPKIT_CHECK_HELP=1, --help also checks that every option of the app is named
// in the man page (the tool tests use this) and fails otherwise.
int run_tool(const std::string& tool, int argc, char** argv, const ToolSetup& setup, const char* man_page);

// The man page (a small roff subset: .TH .SH .SS .PP .TP .IP .B .I .BR .IR .RS .RE .nf .fi .EX .EE)
// rendered as plain text for a terminal.
std::string render_man_page(const char* roff);

// A progress bar on stderr, drawn only when stderr is a terminal. Thread-safe add().
class Progress {
 public:
  Progress(std::string label, long total);
  ~Progress();
  void add(long n = 1);
  void done();

 private:
  struct Impl;
  Impl* impl_;
};

// Warnings go to stderr as "tool: warning: ..."; the tool name is set by run_tool.
void warn(const std::string& message);

// A success summary ("tool: ..." on stderr), printed by run_tool once the run's outputs are committed
// and only then: a run that fails at commit (a target turned out to be a folder, a full disk) prints
// its error, not a summary followed by the error. Lines are printed in the order given.
void summary(const std::string& line);
const std::string& tool_name();

}  // namespace tpkit
