#include "tpkit/atomic_output.hpp"

#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <random>

#include "tpkit/error.hpp"

namespace tpkit {

AtomicOutput::AtomicOutput(const std::string& path) : path_(path) {
  if (path == "-") {
    to_stdout_ = true;
    return;
  }
  std::random_device rd;
  tmp_ = path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(rd() % 1000000);
  file_.open(tmp_, std::ios::out | std::ios::trunc | std::ios::binary);
  if (!file_) throw InputError(path, 0, "cannot open for writing");
}

AtomicOutput::~AtomicOutput() {
  if (!to_stdout_ && !committed_) {
    file_.close();
    std::remove(tmp_.c_str());
  }
}

std::ostream& AtomicOutput::stream() { return to_stdout_ ? std::cout : static_cast<std::ostream&>(file_); }

void AtomicOutput::commit() {
  if (committed_) return;
  if (to_stdout_) {
    std::cout.flush();
    if (!std::cout) throw InputError("-", 0, "write error on standard output");
    committed_ = true;
    return;
  }
  file_.flush();
  if (!file_) throw InputError(path_, 0, "write error");
  file_.close();
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    std::remove(tmp_.c_str());
    throw InputError(path_, 0, "cannot rename the temporary output onto it");
  }
  committed_ = true;
}

void write_file_atomic(const std::string& path, const std::string& content) {
  AtomicOutput out(path);
  out.stream() << content;
  out.commit();
}

}  // namespace tpkit
