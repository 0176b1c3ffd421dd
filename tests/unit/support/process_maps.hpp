// What the kernel says of this process's memory (/proc/self/smaps), for the tests of huge-page advice.
#pragma once
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>

namespace tpkit_test {

// The VmFlags line of the mapping that holds address a, "" if none
inline std::string vm_flags(const void* a) {
  std::ifstream f("/proc/self/smaps");
  const uintptr_t x = reinterpret_cast<uintptr_t>(a);
  bool inside = false;
  for (std::string line; std::getline(f, line);) {
    uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-') {
      inside = lo <= x && x < hi;
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
}

// whether the mapping that holds address a is advised for huge pages (MADV_HUGEPAGE: flag "hg")
inline bool advised_huge(const void* a) { return vm_flags(a).find(" hg") != std::string::npos; }

}  // namespace tpkit_test
