#include "tpkit/core/atomic_output.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <random>
#include <streambuf>
#include <system_error>

#include "tpkit/core/error.hpp"
#include "tpkit/core/huge_pages.hpp"

namespace tpkit {

namespace fs = std::filesystem;

// What a run writes to standard output (or to a device or FIFO), held until the run commits: a list of
// 2 MiB chunks filled in turn, not one string. An ostringstream doubled its string as it grew and then
// copied it whole for the commit: for the 188 MB of a 10000² pair's matches, 730 MB of fresh memory
// written (182 thousand page faults, one in three of the run's), where the chunks take the text once.
// Each chunk is 2 MiB-aligned and advised for transparent huge pages: on Debian ("madvise") a chunk is then
// one fault, not 512; where huge pages are off, ordinary pages.
class OutputBuffer : public std::streambuf {
 public:
  OutputBuffer() = default;
  OutputBuffer(const OutputBuffer&) = delete;
  OutputBuffer& operator=(const OutputBuffer&) = delete;
  ~OutputBuffer() override {
    for (char* c : chunks_) std::free(c);
  }
  // the text, chunk by chunk
  void write_to(std::ostream& os) const {
    for (size_t i = 0; i < chunks_.size() && os; ++i)
      os.write(chunks_[i], static_cast<std::streamsize>(i + 1 < chunks_.size() ? kChunk : pptr() - chunks_[i]));
  }

 protected:
  int_type overflow(int_type ch) override {
    if (traits_type::eq_int_type(ch, traits_type::eof())) return traits_type::not_eof(ch);
    if (!grow()) return traits_type::eof();
    *pptr() = traits_type::to_char_type(ch);
    pbump(1);
    return ch;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    std::streamsize done = 0;
    while (done < n) {
      if (pptr() == epptr() && !grow()) break;
      const std::streamsize k = std::min<std::streamsize>(n - done, epptr() - pptr());
      std::memcpy(pptr(), s + done, static_cast<size_t>(k));
      pbump(static_cast<int>(k));
      done += k;
    }
    return done;
  }

 private:
  static constexpr size_t kChunk = kHugePage;
  bool grow() {
    void* c = std::aligned_alloc(kChunk, kChunk);
    if (!c) return false;
    advise_huge_pages(c, kChunk);
    chunks_.push_back(static_cast<char*>(c));
    setp(chunks_.back(), chunks_.back() + kChunk);
    return true;
  }
  std::vector<char*> chunks_;
};

namespace {

// Live temporary files, readable from a signal handler: fixed slots of strdup'ed names.
constexpr int kSlots = 4096;
std::atomic<char*> g_temps[kSlots];

void register_temp(const std::string& tmp) {
  char* name = ::strdup(tmp.c_str());
  if (!name) return;
  for (auto& slot : g_temps) {
    char* expected = nullptr;
    if (slot.compare_exchange_strong(expected, name)) return;
  }
  std::free(name);  // more live temporaries than slots: this one is not removed on a signal
}

void unregister_temp(const std::string& tmp) {
  for (auto& slot : g_temps) {
    char* p = slot.load();
    if (p && tmp == p && slot.compare_exchange_strong(p, nullptr)) {
      std::free(p);
      return;
    }
  }
}

// Folders created for the run's outputs, in creation order (parents first), readable from a signal
// handler: removed, when empty, on a signal as on a failure.
constexpr int kDirSlots = 4096;
std::atomic<char*> g_dirs[kDirSlots];
std::atomic<int> g_dir_count{0};

void register_dir(const std::string& dir) {
  const int i = g_dir_count.load();
  if (i >= kDirSlots) return;  // more folders than slots: the rest are not removed on a signal
  g_dirs[i].store(::strdup(dir.c_str()));
  g_dir_count.store(i + 1);
}

void forget_dirs() {
  const int n = g_dir_count.exchange(0);
  for (int i = 0; i < n; ++i) std::free(g_dirs[i].exchange(nullptr));
}

extern "C" void remove_temps_on_signal(int sig) {
  for (auto& slot : g_temps) {
    char* p = slot.load();
    if (p) ::unlink(p);
  }
  for (int i = g_dir_count.load() - 1; i >= 0; --i) {
    char* d = g_dirs[i].load();
    if (d) ::rmdir(d);  // only if empty
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

struct Pending {
  std::string tmp, target;
  std::unique_ptr<OutputBuffer> text;
  bool to_stdout = false;  // text for stdout, or (direct) for a device or FIFO named by target
  bool direct = false;
};

// An existing target that is not a regular file (a device such as /dev/null, a FIFO, /dev/stdout):
// written in place, since renaming a temporary file onto it would replace the device node.
bool is_special(const std::string& path) {
  std::error_code ec;
  const auto st = fs::status(path, ec);
  return !ec && fs::exists(st) && !fs::is_regular_file(st) && !fs::is_directory(st);
}

// put(f) writes the text into the opened target
template <class Put>
void write_direct(const std::string& target, Put&& put) {
  std::ofstream f(target, std::ios::out | std::ios::binary);
  if (!f) throw InputError(target, 0, "cannot open for writing: " + std::string(std::strerror(errno)));
  put(f);
  f.flush();
  if (!f) throw InputError(target, 0, "write error: " + std::string(std::strerror(errno)));
}

struct Transaction {
  std::mutex m;
  bool active = false;
  std::vector<Pending> pending;
  struct Claim {
    std::string target, option;  // normalized target; the option that named it ("" for a writer)
    bool reserved;               // by check_outputs(): the first writer of the target takes it over
  };
  std::vector<Claim> claimed;
  std::vector<std::string> inputs;                           // normalized
  std::vector<std::string> stale;
  std::vector<fs::path> made_dirs;  // created for this run, innermost last
};
Transaction& tx() {
  static Transaction t;
  return t;
}

std::string normalized(const std::string& path) {
  if (path == "-") return path;
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  return ec ? fs::absolute(path).lexically_normal().string() : p.string();
}

bool same_file(const std::string& a, const std::string& b) {
  if (a == "-" || b == "-") return a == b;
  if (a == b) return true;
  std::error_code ec;
  return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec);
}

std::string errno_text() { return std::strerror(errno); }

void rename_now(const std::string& tmp, const std::string& target) {
  if (is_special(target)) {  // never replace a device node: copy the finished file into it
    auto drop_tmp = [&] {
      std::remove(tmp.c_str());
      unregister_temp(tmp);
    };
    try {
      std::ifstream in(tmp, std::ios::binary);
      write_direct(target, [&](std::ostream& f) {
        if (in.peek() != std::ifstream::traits_type::eof()) f << in.rdbuf();
      });
    } catch (...) {
      drop_tmp();
      throw;
    }
    drop_tmp();
    return;
  }
  if (std::rename(tmp.c_str(), target.c_str()) != 0) {
    const std::string why = errno_text();
    std::remove(tmp.c_str());
    unregister_temp(tmp);
    throw InputError(target, 0, "cannot rename the temporary output onto it: " + why);
  }
  unregister_temp(tmp);
}

// caller holds the lock
void check_not_input(const std::string& norm, const std::string& path, const std::string& option) {
  for (const auto& in : tx().inputs)
    if (same_file(in, norm))
      throw UsageError((option.empty() ? "" : option + " ") + path + ": is also an input of this run: refusing to overwrite it");
}
}  // namespace

std::string claim_temp(const std::string& target) {
  static std::atomic<unsigned> counter{0};
  std::random_device rd;
  std::string stem = target, ext;
  const auto dot = target.find_last_of('.'), slash = target.find_last_of('/');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash) && dot > (slash == std::string::npos ? 0 : slash + 1)) {
    stem = target.substr(0, dot);
    ext = target.substr(dot);
  }
  const std::string tmp = stem + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++) + "." +
                          std::to_string(rd() % 1000000) + ext;
  register_temp(tmp);
  return tmp;
}

void discard_temp(const std::string& tmp) {
  std::remove(tmp.c_str());
  unregister_temp(tmp);
}

void finish_output(const std::string& tmp, const std::string& target) {
  {
    std::lock_guard<std::mutex> lock(tx().m);
    if (tx().active) {
      tx().pending.push_back({tmp, target, nullptr, false});
      return;
    }
  }
  rename_now(tmp, target);
}

void begin_outputs() {
  std::lock_guard<std::mutex> lock(tx().m);
  Transaction& t = tx();
  t.active = true;
  t.pending.clear();
  t.claimed.clear();
  t.inputs.clear();
  t.stale.clear();
  t.made_dirs.clear();
  forget_dirs();
}

void note_input(const std::string& path) {
  if (path.empty() || path == "-") return;
  std::lock_guard<std::mutex> lock(tx().m);
  if (!tx().active) return;
  const std::string norm = normalized(path);
  for (const auto& c : tx().claimed)
    if (same_file(c.target, norm))
      throw UsageError((c.option.empty() ? "" : c.option + " ") + path + ": is also an input of this run: refusing to overwrite it");
  tx().inputs.push_back(norm);
}

namespace {
// caller holds the lock; `reserve`: a claim by check_outputs() rather than by a writer
void claim_locked(const std::string& path, const std::string& option, bool reserve) {
  const std::string norm = normalized(path);
  for (auto& c : tx().claimed)
    if (c.target == norm) {
      if (c.reserved && !reserve) {  // the writer of a checked output
        c.reserved = false;
        return;
      }
      if (option.empty() && c.option.empty()) throw UsageError(path + ": written twice in one run");
      throw UsageError((option.empty() ? "an output" : option) + " and " + (c.option.empty() ? "another output" : c.option) +
                       " name the same file (" + path + "): one would overwrite the other");
    }
  check_not_input(norm, path, option);
  tx().claimed.push_back({norm, option, reserve});
}
}  // namespace

void claim_output(const std::string& path, const std::string& option) {
  std::lock_guard<std::mutex> lock(tx().m);
  if (tx().active) claim_locked(path, option, false);
}

void check_outputs(const std::vector<std::pair<std::string, std::string>>& option_and_path,
                   const std::vector<std::string>& inputs) {
  for (const auto& in : inputs) note_input(in);
  for (const auto& [option, path] : option_and_path) {
    if (path.empty()) continue;
    {
      std::lock_guard<std::mutex> lock(tx().m);
      if (tx().active) claim_locked(path, option, true);
    }
    if (path == "-") continue;
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw InputError(path, 0, "cannot write: folder " + dir.string() + " does not exist");
    if (::access(dir.c_str(), W_OK) != 0) throw InputError(path, 0, "cannot write in folder " + dir.string() + ": " + errno_text());
    if (fs::is_directory(path, ec)) throw InputError(path, 0, "cannot write: is a folder");
  }
}

void create_output_dir(const std::string& path) {
  // the folders that are missing, outermost first, as create_directories makes them: every prefix of the
  // path as written ("o/new/.." makes o and o/new, though it names o)
  std::vector<fs::path> missing;
  std::error_code ec;
  fs::path prefix;
  for (const fs::path& part : fs::absolute(path, ec)) {
    prefix /= part;
    if (part == "." || part == ".." || part.empty()) continue;
    if (!fs::exists(prefix, ec)) missing.push_back(prefix.lexically_normal());
  }
  fs::create_directories(path, ec);
  if (ec || !fs::is_directory(path)) {
    for (auto it = missing.rbegin(); it != missing.rend(); ++it) fs::remove(*it, ec);  // only those it made, if empty
    throw InputError(path, 0, "cannot create the folder: " + (ec ? ec.message() : "not a folder"));
  }
  std::lock_guard<std::mutex> lock(tx().m);
  if (tx().active)
    for (const fs::path& d : missing) {
      tx().made_dirs.push_back(d);
      register_dir(d.string());
    }
}

void remove_on_commit(const std::string& path) {
  std::lock_guard<std::mutex> lock(tx().m);
  if (tx().active) tx().stale.push_back(path);
  else std::remove(path.c_str());
}

namespace {
// Removes the folders made for the run, innermost first, those that are empty (a failed run's).
void remove_made_dirs(const std::vector<fs::path>& dirs) {
  std::error_code ec;
  for (auto it = dirs.rbegin(); it != dirs.rend(); ++it) fs::remove(*it, ec);  // only if empty
  forget_dirs();
}

void commit_pending(std::vector<Pending>& pending, const std::vector<std::string>& stale);
}  // namespace

void commit_outputs() {
  std::vector<Pending> pending;
  std::vector<std::string> stale;
  std::vector<fs::path> dirs;
  {
    std::lock_guard<std::mutex> lock(tx().m);
    pending.swap(tx().pending);
    stale.swap(tx().stale);
    dirs.swap(tx().made_dirs);
    tx().active = false;
    tx().claimed.clear();
    tx().inputs.clear();
  }
  try {
    commit_pending(pending, stale);
  } catch (...) {
    remove_made_dirs(dirs);  // a failure found at commit leaves no folder the run made, as any failure
    throw;
  }
  forget_dirs();
}

namespace {
void commit_pending(std::vector<Pending>& pending, const std::vector<std::string>& stale) {
  // every target checked before any is replaced, so that a rename that must fail fails before the first
  for (const auto& p : pending) {
    if (p.to_stdout) continue;
    std::error_code ec;
    std::string why;
    if (fs::is_directory(p.target, ec)) why = "cannot write: is a folder";
    else if (::access(p.tmp.c_str(), F_OK) != 0) why = "the temporary output vanished";
    if (!why.empty()) {
      for (const auto& q : pending)
        if (!q.to_stdout) discard_temp(q.tmp);
      throw InputError(p.target, 0, why);
    }
  }
  // Text held for standard output, a device or a FIFO next: a full device (/dev/full) or a closed pipe
  // fails only when written, and nothing has been handed over yet, so such a failure still leaves no
  // output. Once written it cannot be taken back; the renames that follow were all checked above.
  try {
    for (const auto& p : pending)
      if (p.to_stdout) {
        if (p.direct) write_direct(p.target, [&](std::ostream& f) { p.text->write_to(f); });
        else p.text->write_to(std::cout);
      }
    std::cout.flush();
    if (!std::cout) throw InputError("-", 0, "write error on standard output: " + errno_text());
  } catch (...) {
    for (const auto& q : pending)
      if (!q.to_stdout) discard_temp(q.tmp);
    throw;
  }
  for (size_t i = 0; i < pending.size(); ++i) {
    if (pending[i].to_stdout) continue;
    try {
      rename_now(pending[i].tmp, pending[i].target);
    } catch (...) {
      for (size_t k = i + 1; k < pending.size(); ++k)
        if (!pending[k].to_stdout) discard_temp(pending[k].tmp);
      throw;
    }
  }
  for (const auto& s : stale) {
    bool rewritten = false;
    for (const auto& p : pending) rewritten = rewritten || (!p.to_stdout && same_file(p.target, s));
    if (!rewritten) std::remove(s.c_str());
  }
}
}  // namespace

void abort_outputs() {
  std::vector<Pending> pending;
  std::vector<fs::path> dirs;
  {
    std::lock_guard<std::mutex> lock(tx().m);
    pending.swap(tx().pending);
    dirs.swap(tx().made_dirs);
    tx().active = false;
    tx().claimed.clear();
    tx().inputs.clear();
    tx().stale.clear();
  }
  for (const auto& p : pending)
    if (!p.to_stdout) discard_temp(p.tmp);
  remove_made_dirs(dirs);
}

void install_output_signal_cleanup() {
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) std::signal(sig, remove_temps_on_signal);
}

AtomicOutput::AtomicOutput(const std::string& path, bool transactional) : path_(path), transactional_(transactional) {
  if (transactional_) claim_output(path);
  if (path == "-" || is_special(path)) {
    to_stdout_ = true;  // buffered, written at commit: to stdout, or in place to a device or FIFO
    direct_ = path != "-";
    buffer_ = std::make_unique<OutputBuffer>();
    buffer_stream_.rdbuf(buffer_.get());
    return;
  }
  tmp_ = claim_temp(path);
  file_.open(tmp_, std::ios::out | std::ios::trunc | std::ios::binary);
  if (!file_) {
    const std::string why = errno_text();
    discard_temp(tmp_);
    throw InputError(path, 0, "cannot open for writing: " + why);
  }
}

AtomicOutput::~AtomicOutput() {
  if (!to_stdout_ && !committed_) {
    file_.close();
    discard_temp(tmp_);
  }
}

std::ostream& AtomicOutput::stream() { return to_stdout_ ? buffer_stream_ : static_cast<std::ostream&>(file_); }

void AtomicOutput::commit() {
  if (committed_) return;
  if (to_stdout_) {
    // a chunk that could not be had leaves the stream bad: the text is not whole
    if (!buffer_stream_) throw InputError(path_, 0, "write error: no memory left to hold the output");
    {
      std::lock_guard<std::mutex> lock(tx().m);
      if (transactional_ && tx().active) {
        tx().pending.push_back({"", direct_ ? path_ : "-", std::move(buffer_), true, direct_});
        buffer_stream_.rdbuf(nullptr);  // the text is the transaction's now
        committed_ = true;
        return;
      }
    }
    committed_ = true;
    if (direct_) return write_direct(path_, [&](std::ostream& f) { buffer_->write_to(f); });
    buffer_->write_to(std::cout);
    std::cout.flush();
    if (!std::cout) throw InputError("-", 0, "write error on standard output: " + errno_text());
    return;
  }
  file_.flush();
  if (!file_) throw InputError(path_, 0, "write error: " + errno_text());
  file_.close();
  if (!file_) throw InputError(path_, 0, "write error on close: " + errno_text());
  committed_ = true;
  if (transactional_) finish_output(tmp_, path_);
  else rename_now(tmp_, path_);
}

void write_file_atomic(const std::string& path, const std::string& content) {
  AtomicOutput out(path);
  out.stream() << content;
  out.commit();
}

}  // namespace tpkit
