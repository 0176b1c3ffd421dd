// Errors of tpkit. Library code throws; a tool's main() (tool_support.hpp) catches and prints
// "tool: file:line: reason" (or "tool: reason" when no file is involved) and exits non-zero.
#pragma once
#include <stdexcept>
#include <string>

namespace tpkit {

// Bad input: a file, a record or a value that cannot be used. Exit code 1.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& reason) : std::runtime_error(reason), reason_(reason) {}
  InputError(std::string file, long line, const std::string& reason)
      : std::runtime_error(compose(file, line, reason)), file_(std::move(file)), line_(line), reason_(reason) {}
  const std::string& file() const { return file_; }
  long line() const { return line_; }
  const std::string& reason() const { return reason_; }

 private:
  static std::string compose(const std::string& file, long line, const std::string& reason) {
    if (file.empty()) return reason;
    if (line <= 0) return file + ": " + reason;
    return file + ":" + std::to_string(line) + ": " + reason;
  }
  std::string file_;
  long line_ = 0;
  std::string reason_;
};

// Wrong use of a tool (options that do not fit together). Exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A computation that cannot give a meaningful result for this input (degenerate geometry, too few
// points, no convergence). Exit code 1, like bad input.
class NumericalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace tpkit
