#include "binary_stream.hpp"

#include <cerrno>
#include <fstream>
#include <sstream>

#include "tpkit/core/input_file.hpp"

namespace tpkit {

std::string read_binary_file(const std::string& path) {
  std::ifstream in = open_input_file(path, InputKind::regular, true);
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw InputError(path, 0, "read error");
  return s.str();
}

}  // namespace tpkit
