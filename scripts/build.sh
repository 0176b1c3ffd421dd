#!/usr/bin/env bash
# Configures and builds tpkit in Release into build/ (executables in build/bin/).
#   bash scripts/build.sh            everything: tools, tests, benchmarks
#   bash scripts/build.sh tools      the tools only (what the demo needs)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
read -r -a cache_flags <<< "$(bash scripts/compiler-cache.sh)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${cache_flags[@]}" >/dev/null
targets=()
for t in "$@"; do targets+=(--target "$t"); done
cmake --build build -j"$jobs" "${targets[@]}"
