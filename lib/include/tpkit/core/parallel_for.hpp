// f(0) .. f(n - 1) on `threads` workers (the calling thread is one of them), items handed out in
// order; the first exception stops the hand-out and is rethrown once all workers have stopped. When the
// system refuses a worker (an address-space limit such as `ulimit -v`, a process limit), the work goes on
// with the workers that did start, and report_thread_shortfall says so once per process.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace tpkit {

// The largest thread count a tool accepts (--threads): beyond it, a typo, not a machine (OpenCV's pool
// crashes on counts above 65536).
constexpr int kMaxThreads = 1024;

// Says on stderr, the first time in a process, that only `started` of `wanted` workers could start.
void report_thread_shortfall(int wanted, int started);

// How many threads (the calling one included, at most `wanted`) the system lets run at once now: for a
// library that starts its own pool and aborts when one is refused (Ceres' num_threads). Reports a
// shortfall as parallel_for does.
int startable_threads(int wanted);

// Starts a thread running `f`, or returns false (after report_thread_shortfall) when the system refuses
// one; the caller then does the work itself.
template <class F>
bool try_start_thread(std::thread& t, F&& f, int wanted, int started) {
  try {
    t = std::thread(std::forward<F>(f));
    return true;
  } catch (const std::system_error&) {
    report_thread_shortfall(wanted, started);
    return false;
  }
}

template <class F>
void parallel_for(size_t n, int threads, F&& f) {
  std::atomic<size_t> next{0};
  std::exception_ptr err;
  std::mutex m;
  auto work = [&]() {
    for (;;) {
      size_t i = next++;
      if (i >= n) return;
      try {
        f(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(m);
        if (!err) err = std::current_exception();
        next = n;
        return;
      }
    }
  };
  const int w = std::min<int>(std::max(1, threads), static_cast<int>(std::max<size_t>(1, n)));
  std::vector<std::thread> pool;
  pool.reserve(static_cast<size_t>(w - 1));
  for (int k = 1; k < w; ++k) {
    std::thread t;
    if (!try_start_thread(t, work, w, k)) break;
    pool.push_back(std::move(t));
  }
  work();
  for (auto& t : pool) t.join();
  if (err) std::rethrow_exception(err);
}

}  // namespace tpkit
