#!/usr/bin/env bash
# Builds the Debian package of tpkit (the tools, their man pages, share/tpkit, the libraries with their
# headers, CMake package and pkg-config file) into build/package/tpkit_VERSION_ARCH.deb, after building
# the tools (scripts/build.sh tools).
#   bash scripts/package.sh              the package only
#   bash scripts/package.sh --install    and installs it (apt-get install ./FILE, as root or with sudo),
#                                        then runs an installed tool from PATH and finds its man page
set -euo pipefail
cd "$(dirname "$0")/.."
install=0
case "${1:-}" in
  "") ;;
  --install) install=1 ;;
  *) echo "usage: $0 [--install]" >&2; exit 2 ;;
esac
bash scripts/install-deps.sh
bash scripts/build.sh tools
rm -rf build/package
(cd build && cpack -G DEB >/dev/null)
deb=$(ls build/package/tpkit_*.deb)
echo "package: $deb ($(du -k "$deb" | cut -f1) kB)"
dpkg-deb -f "$deb" Depends | sed 's/^/package: depends: /'
[ "$install" = 1 ] || exit 0
SUDO=""
[ "$(id -u)" = 0 ] || SUDO=sudo
# man-db: man and its index of the installed pages
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends man-db "./$deb" >/dev/null
hash -r
echo "package: installed; $(command -v tp-match): $(tp-match --version)"
echo "package: man tp-match: $(man -w tp-match)"
man tp-match 2>/dev/null | grep -q 'tp-match' || { echo "package: man tp-match shows no page" >&2; exit 1; }
# formats other than TIFF and NITF go through the OpenImageIO module the package installs beside the tools
png_dir=$(mktemp -d)
oiiotool --pattern noise:type=uniform:min=0:max=1 256x256 1 -d uint8 -o "$png_dir/noise.png"
tp-match "$png_dir/noise.png" "$png_dir/noise.png" --no-refine -q -o "$png_dir/noise.matches" 2>/dev/null ||
  { echo "package: tp-match cannot read a PNG (its OpenImageIO module)" >&2; tp-match "$png_dir/noise.png" "$png_dir/noise.png" -q -o "$png_dir/x" >&2; exit 1; }
echo "package: tp-match read a PNG through $(dpkg -L tpkit | grep tpkit_oiio.so)"
rm -rf "$png_dir"
