#!/usr/bin/env bash
# Installs the Debian packages tpkit needs, only those that are missing. Debian 12; run as root (or with
# sudo available). Used by scripts/demo.sh and scripts/test.sh, so each is complete on its own.
# openimageio-tools: Debian's libopenimageio-dev ships a CMake config (OpenImageIOTargets.cmake) that
# declares the command-line programs (iconvert, oiiotool, ...) as imported targets and fails when their
# files are missing, yet does not depend on the package that has them. tpkit keeps that config, which
# brings OIIO's own transitive dependencies right, and installs the tools it checks for.
set -euo pipefail
packages=(
  g++ cmake make pkg-config
  ccache  # the build scripts compile through it: a rebuild (and CI's fresh roots, which share one) compiles only what changed
  libeigen3-dev libopencv-dev libopenimageio-dev openimageio-tools libtiff-dev libgeographiclib-dev
  libcli11-dev libceres-dev libnanoflann-dev libsqlite3-dev
  libopenjp2-7-dev  # NITF images compressed with JPEG 2000 (IC=C8/M8) are decoded and written with OpenJPEG
  libproj-dev proj-data libgeotiff-dev  # reference DEMs and GCPs in any CRS and vertical datum (PROJ; EGM96 grid in proj-data; GeoTIFF keys)
  libjpeg-dev  # tp-report's inline pictures of orthos, encoded in memory (OpenCV's imgcodecs would link GDAL)
  nlohmann-json3-dev  # tp-convert reads OpenMVG's sfm_data.json with a JSON parser (a regex scan crashed on long objects)
  libgtest-dev libgmock-dev libbenchmark-dev
  dpkg-dev file  # dpkg-shlibdeps and file (CPack calls it to find the binaries): the Debian package's runtime dependencies (scripts/package.sh)
)
if [ "${1:-}" = "--test" ]; then
  # the sanitizer build and the fuzzers of the test suite use clang and its runtimes
  packages+=(clang libclang-rt-14-dev)
  # groff renders the man pages for their lint test (tests/layout/man_pages.sh)
  packages+=(groff-base)
  # real consumers and engines the tests drive: COLMAP's importer (tp-convert), a single-node Slurm
  # and GNU parallel (tp-plan's job files)
  packages+=(colmap slurm-wlm munge parallel)
  # pictures checked as users see them: SVG figures rendered by librsvg, report pages opened in a
  # headless Chromium
  packages+=(librsvg2-bin chromium)
  # GDAL as a peer only, never linked: gdalinfo reads tp-ortho's GeoTIFF keys back, gdalwarp -rpc is the
  # reference its orthos are compared with (tests/tools/tp-ortho.cmake, bench/ortho_gdalwarp.sh) and
  # makes the orthos tp-report's tests show
  packages+=(gdal-bin)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
t0=$(date +%s)
echo "install-deps: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" != 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: run as root to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: installed ${#missing[@]} packages and their dependencies in $(( $(date +%s) - t0 )) s" >&2
