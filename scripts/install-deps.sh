#!/usr/bin/env bash
# Installs the Debian packages tpkit needs, only those that are missing. Debian 12; run as root (or with
# sudo available). Used by scripts/demo.sh and scripts/test.sh, so each is complete on its own.
set -euo pipefail
packages=(
  g++ cmake make pkg-config
  libeigen3-dev libopencv-dev libopenimageio-dev libtiff-dev libgeographiclib-dev
  libcli11-dev libceres-dev libnanoflann-dev
  libgtest-dev libgmock-dev libbenchmark-dev
)
if [ "${1:-}" = "--test" ]; then
  # the sanitizer build and the fuzzers of the test suite use clang and its runtimes
  packages+=(clang libclang-rt-14-dev)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "install-deps: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" != 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: run as root to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
