// Output that never leaves a half-written file, and a run whose outputs commit together.
//
// AtomicOutput writes to a temporary file in the target's folder (or, for "-" and for an existing
// device or FIFO such as /dev/null, to a buffer written there at commit) and hands it over on commit(). Outside a transaction the temporary file replaces the target at once.
// Inside one (run_tool opens one around every tool's body) the hand-over waits: commit_outputs() renames
// every finished temporary onto its target when the tool has succeeded (after writing the text held for
// stdout and devices, whose write can fail too), abort_outputs() removes them all when it has failed, so
// a failed run leaves no output at all, not some of them. A target claimed
// twice in one transaction (two options naming one file, "-" twice) or one that is an input of the run
// is refused before anything is written. Temporary files are removed on SIGINT, SIGTERM, SIGHUP and
// SIGPIPE (install_output_signal_cleanup), so an interrupted run leaves nothing behind either.
#pragma once
#include <fstream>
#include <memory>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace tpkit {

class OutputBuffer;

class AtomicOutput {
 public:
  // `transactional` = false: the file (a cache entry, say) is committed at once even in a transaction.
  explicit AtomicOutput(const std::string& path, bool transactional = true);
  ~AtomicOutput();
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  std::ostream& stream();
  // Flushes, checks for write errors and hands the file over (see above).
  void commit();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string tmp_;
  std::ofstream file_;
  std::unique_ptr<OutputBuffer> buffer_;  // stdout, a device or a FIFO: held until commit
  std::ostream buffer_stream_{nullptr};
  bool to_stdout_ = false;  // buffered and written at commit: to stdout, or (direct_) in place
  bool direct_ = false;     // the target is an existing device or FIFO (/dev/null): no rename onto it
  bool transactional_ = true;
  bool committed_ = false;
};

// Writes a whole string atomically (see AtomicOutput).
void write_file_atomic(const std::string& path, const std::string& content);

// A temporary name beside `target` that keeps its extension last (image writers pick the format from
// it), registered for removal on a signal. Writers that make their own files (TIFF) use it with
// finish_output() and discard_temp().
std::string claim_temp(const std::string& target);
// The finished temporary `tmp` becomes `target`: now, or at commit_outputs() inside a transaction.
void finish_output(const std::string& tmp, const std::string& target);
// Removes an unfinished temporary file and forgets it.
void discard_temp(const std::string& tmp);

// The transaction of one run. begin_outputs() starts it; claim_output() reserves a target (throws
// UsageError when it is claimed twice or is one of `inputs`); note_input() records a file the run reads;
// remove_on_commit() deletes a stale file of an output set (e.g. a scene folder) when the run commits.
void begin_outputs();
void note_input(const std::string& path);
void claim_output(const std::string& path, const std::string& option = "");
// Checks a tool's outputs before any work: distinct targets (and "-" at most once), none of them an
// input, every folder existing and writable. Empty paths are skipped. `names` name the options.
void check_outputs(const std::vector<std::pair<std::string, std::string>>& option_and_path,
                   const std::vector<std::string>& inputs);
void remove_on_commit(const std::string& path);
// Creates an output folder (and its missing parents); those it created are removed again, when empty,
// if the run fails. Throws InputError when it cannot.
void create_output_dir(const std::string& path);
void commit_outputs();
void abort_outputs();

// Installs the signal handlers that remove live temporary files (run_tool calls it).
void install_output_signal_cleanup();

}  // namespace tpkit
