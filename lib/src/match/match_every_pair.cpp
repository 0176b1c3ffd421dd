#include "tpkit/match/match_every_pair.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <future>
#include <thread>

#include "tpkit/match/keypoint_cache.hpp"
#include "tpkit/core/parallel_for.hpp"

namespace tpkit {

void match_every_pair(const std::vector<ImageSource>& src, const PairMatchOptions& o,
                      const std::vector<const RpcModel*>& rpc,
                      const std::function<void(size_t, size_t, Matches&, const PairMatchStats&)>& on_pair,
                      double* detect_seconds) {
  const size_t n = src.size();
  const int T = std::max(1, o.threads);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Keypoints> K(n);
  std::vector<char> cached(n, 0);
  std::vector<std::promise<void>> ready(n);
  std::vector<std::shared_future<void>> detected(n);
  for (size_t i = 0; i < n; ++i) detected[i] = ready[i].get_future().share();
  std::atomic<int> free_threads{T};  // threads detection leaves to a pair matched beside it (at least 1)
  std::atomic<bool> done{false};
  double dt = 0;

  auto detect_all = [&]() {
    auto detect = [&](size_t i, int threads) {
      try {
        bool c = false;
        K[i] = detect_sift_cached(src[i], o.sift, threads, o.cache_dir, nullptr, &c);
        cached[i] = c;
        ready[i].set_value();
      } catch (...) {
        ready[i].set_exception(std::current_exception());
      }
    };
    // concurrent_sift_calls images at a time (sift_tiles.hpp), each with two threads' share. Marseille
    // triplet, 2 threads, one run for the three pairs: detection 2.3-4.3 s -> 1.9-2.0 s, whole run
    // 4.8-6.9 -> 4.4-4.5 s, peak memory 494-541 -> 333 MB against two images at a time (the VM this was
    // measured on backs fresh memory lazily: ~2.5 ms a MB mapped for the first time).
    const int at_once = concurrent_sift_calls(T);
    free_threads = 1;  // a pair matched beside detection gets one thread
    parallel_for(n, at_once, [&](size_t i) { detect(i, std::max(1, T / at_once)); });
    dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    free_threads = T;
    done = true;
  };

  std::thread detector;
  if (T == 1 || !try_start_thread(detector, detect_all, T, 1)) detect_all();
  struct Join {
    std::thread& t;
    ~Join() {
      if (t.joinable()) t.join();
    }
  } join{detector};

  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      detected[i].get();
      detected[j].get();
      PairMatchOptions po = o;
      po.rpc1 = po.rpc2 = nullptr;
      if (rpc.size() == n && rpc[i] && rpc[j]) po.rpc1 = rpc[i], po.rpc2 = rpc[j];
      if (!done) {  // beside detection: the threads it leaves, all of them once it ends (from the next band)
        po.threads = free_threads.load();
        po.live_threads = &free_threads;
      }
      PairMatchStats st;
      Matches m = match_keypoints(src[i], src[j], K[i], K[j], po, &st);
      st.cached1 = cached[i];
      st.cached2 = cached[j];
      on_pair(i, j, m, st);
    }
  if (detector.joinable()) detector.join();
  if (detect_seconds) *detect_seconds = dt;
}

}  // namespace tpkit
