#!/usr/bin/env bash
# `cmake --install` of a build into a scratch prefix, and what a user of the installed tree does: every
# tool runs from PATH and answers --version, every man page is there and renders without a warning (man
# finds it through MANPATH), share/tpkit holds the data, and an outside project builds against the
# library and runs, once through find_package(tpkit) and once through pkg-config.
#   install_tree.sh SOURCE_DIR BUILD_DIR WORK_DIR
set -euo pipefail
[ $# -eq 3 ] || { echo "usage: $0 SOURCE_DIR BUILD_DIR WORK_DIR" >&2; exit 2; }
src=$1 build=$2 work=$3
fail() { echo "install: $*" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null

# the tools, from PATH
tools=$(cd "$src/tools" && ls *.cpp | sed 's/\.cpp$//')
for t in $tools; do
  [ -x "$prefix/bin/$t" ] || fail "bin/$t: not installed"
  PATH=$prefix/bin:/usr/bin:/bin "$t" --version | grep -q "^$t (tpkit) " || fail "$t --version from the installed tree"
done
[ "$(ls "$prefix/bin" | wc -l)" = "$(echo "$tools" | wc -w)" ] || fail "bin/ holds more than the tools: $(ls "$prefix/bin")"

# the man pages, where man looks
for page in "$src"/man/*.[157]; do
  name=$(basename "$page"); sec=${name##*.}
  inst=$prefix/share/man/man$sec/$name
  cmp -s "$page" "$inst" || fail "share/man/man$sec/$name: not installed"
  warnings=$(groff -ww -man -Tutf8 "$inst" 2>&1 >/dev/null)
  [ -z "$warnings" ] || fail "$inst: $warnings"
done
if command -v man >/dev/null; then
  [ "$(MANPATH=$prefix/share/man man -w tp-match)" = "$prefix/share/man/man1/tp-match.1" ] || fail "man -w tp-match: not the installed page"
  [ "$(MANPATH=$prefix/share/man man -w tpkit)" = "$prefix/share/man/man7/tpkit.7" ] || fail "man -w tpkit: not the installed overview"
fi
for f in "$src"/share/tpkit/*; do cmp -s "$f" "$prefix/share/tpkit/$(basename "$f")" || fail "share/tpkit/$(basename "$f"): not installed"; done
[ -f "$prefix/include/tpkit/core/formats.hpp" ] || fail "include/tpkit/core/formats.hpp: not installed"

# an outside project, through CMake's package and through pkg-config
cmake -S "$src/tests/install/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/consumer" >/dev/null
out=$("$work/consumer/consumer" "$prefix/share/tpkit/cluster-a.points")
[[ $out == "100 points, tpkit "* ]] || fail "consumer (find_package): $out"
# shellcheck disable=SC2046
g++ -std=c++17 -O1 "$src/tests/install/consumer/main.cpp" -o "$work/consumer-pc" \
  $(PKG_CONFIG_PATH=$prefix/lib/pkgconfig pkg-config --cflags --libs tpkit)
out=$("$work/consumer-pc" "$prefix/share/tpkit/cluster-a.points")
[[ $out == "100 points, tpkit "* ]] || fail "consumer (pkg-config): $out"
echo "install: $(echo "$tools" | wc -w) tools, $(ls "$src"/man/*.[157] | wc -l) man pages, headers, libraries, CMake package and pkg-config file under $prefix"
