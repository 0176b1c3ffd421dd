// parallel_for when the system refuses worker threads: every item is still done exactly once, by the
// workers that started, and an exception still reaches the caller.
#include "tpkit/core/parallel_for.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

#include "../limited_process.hpp"

namespace {

using tpkit_test::kSanitized;
using tpkit_test::run_limited;

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
