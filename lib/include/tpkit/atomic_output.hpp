// Output that never leaves a half-written file: data goes to a temporary file in the same folder,
// which replaces the target only on commit(). "-" writes to stdout. Without commit() (an exception
// on the way), the temporary file is removed and the target is untouched.
#pragma once
#include <fstream>
#include <ostream>
#include <string>

namespace tpkit {

class AtomicOutput {
 public:
  explicit AtomicOutput(const std::string& path);
  ~AtomicOutput();
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  std::ostream& stream();
  // Flushes, checks for write errors and renames the temporary file onto the target.
  void commit();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string tmp_;
  std::ofstream file_;
  bool to_stdout_ = false;
  bool committed_ = false;
};

// Writes a whole string atomically (see AtomicOutput).
void write_file_atomic(const std::string& path, const std::string& content);

}  // namespace tpkit
