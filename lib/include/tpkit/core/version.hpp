// tpkit's version: the CMake project version, and `git describe` of the checkout it was built from
// where there is one (e.g. "0.1.0 (git 2c52c20a1b-dirty)"). Written by every tool's --version and in the
// "# written-by:" line of every file tpkit writes.
#pragma once
#include <string>

namespace tpkit {

// The project version alone, "MAJOR.MINOR.PATCH".
const char* version();
// The project version and, where the build had a git checkout, its description.
const char* version_full();
// "TOOL VERSION" (the running tool's name, see tool_support.hpp, and version_full()): the writer named in
// every output file (text headers, TIFF Software tag, SVG comment).
std::string written_by();

}  // namespace tpkit
