#include "tpkit/core/parallel_for.hpp"

#include <condition_variable>

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

int startable_threads(int wanted) {
  wanted = std::max(1, wanted);
  std::mutex m;
  std::condition_variable cv;
  bool release = false;
  std::vector<std::thread> pool;
  pool.reserve(static_cast<size_t>(wanted - 1));
  int started = 1;  // the calling thread
  for (int k = 1; k < wanted; ++k) {
    std::thread t;
    if (!try_start_thread(t, [&] {
          std::unique_lock<std::mutex> lock(m);
          cv.wait(lock, [&] { return release; });
        }, wanted, started))
      break;
    pool.push_back(std::move(t));
    ++started;
  }
  {
    std::lock_guard<std::mutex> lock(m);
    release = true;
  }
  cv.notify_all();
  for (auto& t : pool) t.join();
  return started;
}

}  // namespace tpkit
