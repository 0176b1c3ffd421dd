#include "binary_stream.hpp"

#include <cerrno>
#include <fstream>
#include <sstream>

namespace tpkit {

std::string read_binary_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open: " + std::string(std::strerror(errno)));
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw InputError(path, 0, "read error");
  return s.str();
}

}  // namespace tpkit
