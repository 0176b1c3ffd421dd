// Opening an input file, with the messages every tool gives for one that cannot be read:
// "FILE: is a directory", "FILE: no such file", "FILE: cannot open for reading: REASON" (InputError),
// and reading text from it line by line with a bound, so that a device, a binary file or a file with no
// line break fails at once ("FILE:LINE: binary data ...") instead of filling memory.
//
// Without these checks a directory opens as a stream (std::ifstream succeeds on Linux) and the first
// read throws std::ios_base::failure "basic_filebuf::underflow error reading the file: Is a directory",
// which names no file.
#pragma once
#include <filesystem>
#include <fstream>
#include <istream>
#include <memory>
#include <string>

namespace tpkit {

// What an input may be.
enum class InputKind {
  stream,   // a regular file, a pipe (FIFO, process substitution) or a device such as /dev/stdin
  file,     // a regular file or a pipe: no device (a list, a peer format's file)
  regular,  // a regular file only (binary files read whole)
  image,    // a regular file only, said so for an image: it is read by random access (headers, tiles, blocks
            // at their offsets), which a device or a pipe does not give, and read by format readers
            // (libtiff, OpenImageIO) that would block on a FIFO or never reach the end of /dev/zero
};

// Throws InputError(path, 0, reason) unless `path` names something of that kind that can be read.
void check_input_file(const std::string& path, InputKind kind = InputKind::stream);

// check_input_file, then the file opened (note_input(path) recorded: no output of the run may replace it).
std::ifstream open_input_file(const std::string& path, InputKind kind = InputKind::stream, bool binary = false);

// The longest line a text reader takes.
constexpr size_t kMaxTextLine = size_t(1) << 20;

// One line into `line`, without its '\n' (a trailing '\r' is kept); false at the end of the stream.
// Throws InputError(source, lineno, ...) for a NUL byte (binary data) or a line longer than max_line.
bool read_text_line(std::istream& in, std::string& line, const std::string& source, long lineno,
                    size_t max_line = kMaxTextLine);

// KIND when `line` is a tpkit header "# tpkit KIND VERSION" (text_table.hpp), "" for any other line.
std::string tpkit_header_kind(const std::string& line);

// A text input opened once (a path, or "-" for stdin) whose first line is read (bounded, as read_text_line
// reads it) and kept, then given back by stream() before the rest: a reader that picks how to parse an
// input by its header (the kind "# tpkit KIND VERSION" names, on the first line) looks at it without
// opening the input twice, which a pipe does not allow (its second reading is empty or the rest), and
// without reading it whole.
class TextInput {
 public:
  explicit TextInput(const std::string& path);
  ~TextInput();
  // The first line ("" for an empty input), a UTF-8 byte order mark removed.
  const std::string& first_line() const { return first_; }
  // tpkit_header_kind(first_line()).
  std::string header_kind() const;
  // The whole input, its first line as first_line() gives it, to be read once.
  std::istream& stream() { return in_; }

 private:
  class Replay;
  std::ifstream file_;
  std::string first_;
  std::unique_ptr<Replay> replay_;
  std::istream in_{nullptr};
};

// A std::filesystem error in the project's words, "PATH: what failed: reason" (libstdc++'s own text,
// "filesystem error: what failed: reason [PATH]", puts the file last and the library first): for a tool's
// main() and any page or message that shows an error to a person.
std::string filesystem_error_message(const std::filesystem::filesystem_error& e);

}  // namespace tpkit
