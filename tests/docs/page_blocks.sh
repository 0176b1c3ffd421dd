#!/usr/bin/env bash
# The command blocks of one documentation page (README.md or docs/NAME.md), run as a new user runs them:
# taken from the page itself, in order, in one shell (a block may use what an earlier one set: PATH, D),
# from a scratch top-level folder of its own that holds the repository's files (linked), build/ (the
# build under test) and ../shared beside it. Every ```sh block runs, except one right after a line
#     <!-- docs-test: not run: REASON -->
# (the test prints it with its reason). A failing command fails the test, naming its page and line.
# Then tests/docs/figures/STEM.sh (STEM: the page's file name without .md), when there is one, checks
# the figures the page states on the files the blocks wrote; it runs in the same folder, with the
# blocks' output in $log and the helpers below.
#   page_blocks.sh REPO BUILD_DIR SHARED_DIR WORK_DIR PAGE        (PAGE relative to REPO)
set -euo pipefail
[ $# -eq 5 ] || { echo "usage: $0 REPO BUILD_DIR SHARED_DIR WORK_DIR PAGE" >&2; exit 2; }
repo=$1 build=$2 shared=$3 work=$4 page=$5
here=$(cd "$(dirname "$0")" && pwd)
source "$here/scratch_top.sh"
stem=$(basename "$page" .md)
[ -f "$repo/$page" ] || { echo "docs: $page: no such page" >&2; exit 2; }
scratch_top "$repo" "$build" "$shared" "$work"

# ---- the blocks -------------------------------------------------------------------------------------
# blocks/NNN-LINE.sh for each block that runs; skipped.txt "LINE: REASON" for the others
mkdir -p "$work/blocks"
awk -v dir="$work/blocks" -v skipped="$work/blocks/skipped.txt" '
  /^<!-- docs-test: not run: / { reason = $0; sub(/^<!-- docs-test: not run: /, "", reason); sub(/ -->$/, "", reason); next }
  !inside && /^```sh$/ {
    inside = 1; n++; start = NR + 1
    if (reason != "") { skip = 1; print start ": " reason > skipped }
    else { skip = 0; file = sprintf("%s/%03d-%d.sh", dir, n, start) }
    reason = ""; next
  }
  inside && /^```$/ { inside = 0; next }
  inside { if (!skip) print > file; next }
  /[^ ]/ { reason = "" }
' "$repo/$page"
touch "$work/blocks/skipped.txt"
blocks=("$work"/blocks/[0-9]*.sh)
[ -e "${blocks[0]}" ] || { echo "docs: $page: no command block to run" >&2; exit 1; }
while read -r line; do echo "docs: $page:$line (not run)"; done < "$work/blocks/skipped.txt"

# one shell for all blocks, as a user pastes them one after the other
{
  echo 'set -eEo pipefail'
  echo 'trap '\''echo "docs: '"$page"':$((page_line + LINENO - block_start)): failed: $BASH_COMMAND" >&2'\'' ERR'
  for b in "${blocks[@]}"; do
    line=${b##*-}; line=${line%.sh}
    echo "echo '== $page:$line' >&2"
    echo "page_line=$line; block_start=\$((LINENO + 1))"
    cat "$b"
  done
} > "$work/blocks/all.sh"
bash "$work/blocks/all.sh" 2>&1 | tee "$work/blocks/all.log"

# ---- what the page says these runs give ---------------------------------------------------------------
log=$work/blocks/all.log
fail() { echo "docs: $page: $*" >&2; exit 1; }
records() { grep -vc '^#' "$1"; }
header() { awk -v k="# $1:" 'index($0, k) == 1 { print $3; exit }' "$2"; }
within() { awk -v v="$1" -v lo="$2" -v hi="$3" 'BEGIN { exit !(v >= lo && v <= hi) }'; }
figures=$here/figures/$stem.sh
if [ -f "$figures" ]; then
  source "$figures"
  echo "docs: $page: ${#blocks[@]} blocks ran; $(wc -l < "$work/blocks/skipped.txt") not run; figures as stated"
else
  echo "docs: $page: ${#blocks[@]} blocks ran; $(wc -l < "$work/blocks/skipped.txt") not run; no figures to check"
fi
