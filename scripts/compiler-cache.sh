#!/usr/bin/env bash
# Prints the CMake options that compile through ccache when it is installed (nothing otherwise), for the
# build scripts: cmake -S . -B build $(bash scripts/compiler-cache.sh). A cache hit is the object the same
# compiler made from the same preprocessed source and flags, so it changes no result; CCACHE_DIR (set by
# scripts/fresh-check.sh to a cache its roots share) says where it lives.
set -euo pipefail
command -v ccache >/dev/null || exit 0
echo "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache"
