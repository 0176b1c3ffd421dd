// What unit tests of bounded memory share (not a test itself: no .cpp): whether this build runs under the
// sanitizers (their shadow memory needs more address space than any limit a test sets), and a body run in a
// child process whose address space is limited.
#pragma once
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace tpkit_test {

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
// (0 = the body returned true, 10 = the limit could not be set, 128 + N = killed by signal N).
template <class F>
int run_limited(rlim_t bytes, F body) {
  const pid_t pid = fork();
  if (pid == 0) {
    rlimit lim{bytes, bytes};
    if (setrlimit(RLIMIT_AS, &lim) != 0) _exit(10);
    try {
      _exit(body() ? 0 : 1);
    } catch (...) {
      _exit(1);  // not on into the caller's code (the rest of a test program) in the child
    }
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace tpkit_test
