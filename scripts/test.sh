#!/usr/bin/env bash
# The whole test suite, complete on its own on a fresh Debian 12 machine (as root): installs what is
# missing, builds in Release and runs every test; then builds the tests with AddressSanitizer +
# UndefinedBehaviorSanitizer and runs them (tests labelled 'slow' or named '*Slow*' are left to the
# Release run, and so are those labelled 'rlimit', which run under `ulimit -v`: the sanitizers' shadow
# memory needs more address space than any such limit); then
# builds the libFuzzer targets of the text-format readers and runs each for a short while.
#   TPKIT_FUZZ_SECONDS (default 20)  time per fuzz target; 0 skips the fuzzers
#   TPKIT_SKIP_ASAN=1                skip the sanitizer build
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
stamp() { echo "== $1 ($(( $(date +%s) - start )) s)"; }
stamp "Debian packages (scripts/install-deps.sh --test)"
bash scripts/install-deps.sh --test
jobs=$(nproc 2>/dev/null || echo 2)
read -r -a cache_flags <<< "$(bash scripts/compiler-cache.sh)"

stamp "Release build"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${cache_flags[@]}" >/dev/null
cmake --build build -j"$jobs"

if [ "${TPKIT_SKIP_ASAN:-0}" != 1 ]; then
  stamp "AddressSanitizer + UndefinedBehaviorSanitizer build"
  # -O1 -g1 (line tables only): the sanitizer build was half of CI's time at -O2 -g; a heavy source file
  # (rpc_adjust.cpp, Ceres) compiles in 22 s instead of 59 s, and the reports still name file and line
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
    -DTPKIT_SANITIZE=ON -DTPKIT_BENCH=OFF "${cache_flags[@]}" >/dev/null
  cmake --build build-asan -j"$jobs"
  stamp "sanitizer tests"
  # intercept_tls_get_addr=0: GCC 12's runtime (Debian 12) takes a dynamic TLS block that malloc put 16
  # bytes into a page for a glibc <= 2.18 block, reads its bounds from the words before it, and at exit
  # LeakSanitizer's tracer dies on them ("Tracer caught signal 11") after the test has passed
  # (google/sanitizers#1322). The image module and the libraries it loads have such blocks; where malloc
  # puts them depends on the environment, so CI's fresh roots failed where a developer's machine passed.
  # The cost: pointers held only in those blocks are not leak roots.
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:intercept_tls_get_addr=0 \
  LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan -j"$jobs" -LE 'slow|rlimit' -E 'Slow' --output-on-failure --timeout 900
fi

fuzz_seconds=${TPKIT_FUZZ_SECONDS:-20}
if [ "$fuzz_seconds" != 0 ]; then
  stamp "libFuzzer targets of the readers"
  cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DTPKIT_FUZZ=ON -DTPKIT_TESTS=OFF -DTPKIT_BENCH=OFF "${cache_flags[@]}" >/dev/null
  cmake --build build-fuzz -j"$jobs" --target fuzz_readers
  for kind in matches tracks points trifocal homography cameras nitf; do
    corpus=$(mktemp -d)
    cp fuzz/corpus/"$kind"/* "$corpus"/
    echo "fuzz_$kind: ${fuzz_seconds} s"
    (cd "$corpus" && "$OLDPWD"/build-fuzz/bin/fuzz_"$kind" -max_total_time="$fuzz_seconds" -print_final_stats=1 "$corpus" 2>&1 | tail -n 3)
    rm -rf "$corpus"
  done
fi

stamp "Release tests (all)"
ctest --test-dir build -j"$jobs" --output-on-failure --timeout 1200
command -v ccache >/dev/null && echo "compiler cache: $(ccache --print-stats 2>/dev/null | awk '$1 == "direct_cache_hit" || $1 == "preprocessed_cache_hit" { h += $2 } $1 == "cache_miss" { m = $2 } END { printf "%d hits, %d misses", h, m }')"
stamp "done"
