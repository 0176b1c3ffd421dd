#include "tpkit/core/input_file.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iostream>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"

namespace tpkit {

void check_input_file(const std::string& path, InputKind kind) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) throw InputError(path, 0, "no such file");
    throw InputError(path, 0, std::string("cannot open for reading: ") + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode)) throw InputError(path, 0, "is a directory");
  const bool regular = S_ISREG(st.st_mode), pipe = S_ISFIFO(st.st_mode);
  if (kind == InputKind::regular && !regular) throw InputError(path, 0, "not a regular file");
  if (kind == InputKind::image && !regular) throw InputError(path, 0, "not a regular file: an image must be a file");
  if (kind == InputKind::file && !regular && !pipe) throw InputError(path, 0, "not a regular file or a pipe");
}

std::ifstream open_input_file(const std::string& path, InputKind kind, bool binary) {
  check_input_file(path, kind);
  note_input(path);
  std::ifstream in(path, binary ? std::ios::in | std::ios::binary : std::ios::in);
  if (!in) throw InputError(path, 0, std::string("cannot open for reading: ") + std::strerror(errno));
  return in;
}

bool read_text_line(std::istream& in, std::string& line, const std::string& source, long lineno, size_t max_line) {
  line.clear();
  std::streambuf* sb = in.rdbuf();
  if (!sb) return false;
  for (;;) {
    int c;
    try {
      c = sb->sbumpc();
    } catch (const std::ios_base::failure&) {  // libstdc++'s filebuf throws on a failed read(2)
      throw InputError(source, lineno, std::string("read error: ") + std::strerror(errno));
    }
    if (c == std::char_traits<char>::eof()) return !line.empty();
    if (c == '\n') return true;
    if (c == 0) throw InputError(source, lineno, "binary data (NUL byte) in a text file");
    if (line.size() >= max_line)
      throw InputError(source, lineno, "line longer than " + std::to_string(max_line) + " bytes: not a text file");
    line.push_back(static_cast<char>(c));
  }
}

// The line read ahead, then the rest of the source in blocks (a block at a time, not a byte: a tracks file
// of millions of lines is read through it).
class TextInput::Replay : public std::streambuf {
 public:
  Replay(std::string head, std::streambuf* rest) : head_(std::move(head)), rest_(rest) {
    setg(head_.data(), head_.data(), head_.data() + head_.size());
  }

 protected:
  int_type underflow() override {
    const std::streamsize n = rest_->sgetn(block_, sizeof block_);
    if (n <= 0) return traits_type::eof();
    setg(block_, block_, block_ + n);
    return traits_type::to_int_type(block_[0]);
  }

 private:
  std::string head_;
  std::streambuf* rest_;
  char block_[1 << 16];
};

TextInput::TextInput(const std::string& path) {
  std::istream* src = &std::cin;
  if (path != "-") {
    file_ = open_input_file(path, InputKind::stream, true);
    src = &file_;
  }
  const std::string source = path == "-" ? "<stdin>" : path;
  std::string head;
  const bool line = read_text_line(*src, first_, source, 1);
  if (first_.compare(0, 3, "\xEF\xBB\xBF") == 0) first_.erase(0, 3);  // a UTF-8 byte order mark, gone from stream() too
  if (line) head = first_ + '\n';
  replay_ = std::make_unique<Replay>(std::move(head), src->rdbuf());
  in_.rdbuf(replay_.get());
}

TextInput::~TextInput() = default;

std::string tpkit_header_kind(const std::string& line) {
  std::istringstream ls(line);
  std::string hash, tpkit, kind, more;
  long version = 0;
  if (!(ls >> hash >> tpkit >> kind >> version) || hash != "#" || tpkit != "tpkit") return "";
  return ls >> more ? "" : kind;
}

std::string TextInput::header_kind() const { return tpkit_header_kind(first_); }

std::string filesystem_error_message(const std::filesystem::filesystem_error& e) {
  std::string what = e.what();
  const std::string prefix = "filesystem error: ";
  if (what.compare(0, prefix.size(), prefix) == 0) what.erase(0, prefix.size());
  const std::string paths = e.path1().empty() ? "" : e.path1().string() + (e.path2().empty() ? "" : ", " + e.path2().string());
  if (!paths.empty()) what.erase(std::min(what.size(), what.find(" [" + e.path1().string() + "]")));
  return paths.empty() ? what : paths + ": " + what;
}

}  // namespace tpkit
