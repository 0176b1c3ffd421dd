// parallel_for when the system refuses worker threads: every item is still done exactly once, by the
// workers that started, and an exception still reaches the caller.
#include "tpkit/core/parallel_for.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <stdexcept>
#include <vector>

namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

// Runs `body` in a child process whose address space is limited to `bytes`; returns its exit status
// (0 = the body returned true).
template <class F>
int run_limited(rlim_t bytes, F body) {
  const pid_t pid = fork();
  if (pid == 0) {
    rlimit lim{bytes, bytes};
    if (setrlimit(RLIMIT_AS, &lim) != 0) _exit(10);
    _exit(body() ? 0 : 1);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

TEST(ParallelFor, EveryItemOnceWithFewerThreadsThanAsked) {
  if (kSanitized) GTEST_SKIP() << "the sanitizers' shadow memory needs more address space than the limit";
  // 1000 threads of 8 MiB stacks do not fit in 2 GB: most are refused
  const int rc = run_limited(rlim_t(2) << 30, []() {
    std::vector<std::atomic<int>> done(5000);
    tpkit::parallel_for(done.size(), 1000, [&](size_t i) { done[i]++; });
    for (auto& d : done)
      if (d != 1) return false;
    return true;
  });
  EXPECT_EQ(rc, 0);
}

TEST(ParallelFor, ExceptionReachesTheCallerWithFewerThreads) {
  if (kSanitized) GTEST_SKIP() << "the sanitizers' shadow memory needs more address space than the limit";
  const int rc = run_limited(rlim_t(2) << 30, []() {
    try {
      tpkit::parallel_for(5000, 1000, [&](size_t i) {
        if (i == 4000) throw std::runtime_error("item 4000");
      });
    } catch (const std::runtime_error& e) {
      return std::string(e.what()) == "item 4000";
    }
    return false;
  });
  EXPECT_EQ(rc, 0);
}

TEST(ParallelFor, AllItemsWithoutLimit) {
  std::vector<std::atomic<int>> done(1000);
  tpkit::parallel_for(done.size(), 8, [&](size_t i) { done[i] += static_cast<int>(i); });
  for (size_t i = 0; i < done.size(); ++i) EXPECT_EQ(done[i], static_cast<int>(i));
}

}  // namespace
