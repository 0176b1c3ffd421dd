// f(0) .. f(n - 1) on `threads` workers (the calling thread is one of them), items handed out in
// order; the first exception stops the hand-out and is rethrown once all workers have stopped.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace tpkit {

// The largest thread count a tool accepts (--threads): beyond it, a typo, not a machine (OpenCV's pool
// crashes on counts above 65536).
constexpr int kMaxThreads = 1024;

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
  std::vector<std::thread> pool;
  int w = std::min<int>(std::max(1, threads), static_cast<int>(std::max<size_t>(1, n)));
  for (int k = 1; k < w; ++k) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (err) std::rethrow_exception(err);
}

}  // namespace tpkit
