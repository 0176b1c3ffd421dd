#include "tpkit/core/parallel_for.hpp"

#include <atomic>
#include <string>

#include "tpkit/core/tool_support.hpp"

namespace tpkit {

void report_thread_shortfall(int wanted, int started) {
  static std::atomic<bool> said{false};
  if (said.exchange(true)) return;
  warn("the system refused a worker thread (an address-space or process limit?): going on with " +
       std::to_string(started) + " of the " + std::to_string(wanted) + " threads asked for");
}

}  // namespace tpkit
