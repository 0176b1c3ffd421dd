#!/usr/bin/env bash
# The house's arrows: tools -> components -> core, never back up. Reads the component graph declared in
# lib/CMakeLists.txt (tpkit_component(NAME DEPS tpkit_x ...)) and checks that
#   - every public header sits in lib/include/tpkit/<component>/ with a component that exists,
#   - every #include "tpkit/<c>/..." in lib/ names its own component or one it depends on (transitively),
#   - every source in lib/src/<component>/ has its header beside the others of that component (or is a
#     private helper with a header in the same source folder).
# Exits 1 with one line per violation.
#   layering.sh [SOURCE_DIR]
set -euo pipefail
src=${1:-$(cd "$(dirname "$0")/../.." && pwd)}
cd "$src"
declare -A deps
while read -r name rest; do
  deps[$name]=$(echo "$rest" | grep -oE 'tpkit_[a-z]+' | sed 's/tpkit_//' | tr '\n' ' ' || true)
done < <(sed -nE 's/^tpkit_component\(([a-z]+) DEPS (.*)\)$/\1 \2/p' lib/CMakeLists.txt)
# the opencv interface target is not a component
closure() {  # closure C -> C and every component it reaches
  local seen=" $1 " todo=("$1") c d
  while [ ${#todo[@]} -gt 0 ]; do
    c=${todo[0]}; todo=("${todo[@]:1}")
    for d in ${deps[$c]:-}; do
      [ -n "${deps[$d]+x}" ] || continue
      case $seen in *" $d "*) ;; *) seen+="$d "; todo+=("$d") ;; esac
    done
  done
  echo "$seen"
}
bad=0
fail() { echo "layering: $*"; bad=1; }
for h in lib/include/tpkit/*; do
  [ -d "$h" ] || fail "$h: a public header outside a component folder (lib/include/tpkit/<component>/)"
done
for d in lib/include/tpkit/*/; do
  c=$(basename "$d")
  [ -n "${deps[$c]+x}" ] || fail "$d: no component '$c' in lib/CMakeLists.txt"
done
for f in $(find lib -name '*.cpp' -o -name '*.hpp' | sort); do
  case $f in
    lib/include/tpkit/*/*) c=${f#lib/include/tpkit/}; c=${c%%/*} ;;
    lib/src/*/*) c=${f#lib/src/}; c=${c%%/*} ;;
    *) continue ;;
  esac
  allowed=$(closure "$c")
  while IFS=: read -r line inc; do
    t=$(echo "$inc" | sed -nE 's/.*"tpkit\/([a-z]+)\/[a-z_0-9]+\.hpp".*/\1/p')
    if [ -z "$t" ]; then
      fail "$f:$line: includes a tpkit header outside the component layout: $inc"
    else
      case $allowed in *" $t "*) ;; *) fail "$f:$line: component '$c' includes '$t', which it does not depend on (lib/CMakeLists.txt)" ;; esac
    fi
  done < <(grep -nE '#include [<"]tpkit/' "$f" | sed -E 's/^([0-9]+):/\1:/')
done
for f in $(find tools bench tests fuzz -name '*.cpp' -o -name '*.hpp' | sort); do
  while IFS=: read -r line inc; do
    echo "$inc" | grep -qE '"tpkit/[a-z]+/[a-z_0-9]+\.hpp"' || fail "$f:$line: includes a tpkit header outside the component layout: $inc"
  done < <(grep -nE '#include [<"]tpkit/' "$f" || true)
done
[ $bad = 0 ] && echo "layering: $(find lib/include/tpkit -name '*.hpp' | wc -l) headers in ${#deps[@]} components, every include follows lib/CMakeLists.txt"
exit $bad
