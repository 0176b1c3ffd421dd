// Reads a points file with the installed library and prints its size and tpkit's version.
#include <cstdio>
#include <exception>

#include "tpkit/core/formats.hpp"
#include "tpkit/core/version.hpp"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  try {
    const tpkit::Points p = tpkit::read_points(argv[1]);
    std::printf("%zu points, tpkit %s\n", p.size(), tpkit::version());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
  return 0;
}
