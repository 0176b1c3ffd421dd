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

// A std::filesystem error in the project's words, "PATH: what failed: reason" (libstdc++'s own text,
// "filesystem error: what failed: reason [PATH]", puts the file last and the library first): for a tool's
// main() and any page or message that shows an error to a person.
std::string filesystem_error_message(const std::filesystem::filesystem_error& e);

}  // namespace tpkit
