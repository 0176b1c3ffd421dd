#!/usr/bin/env bash
# The README's command blocks, run as a new user runs them: taken from README.md itself, in order, in one
# shell (a block may use what an earlier one set: PATH, D), from a scratch top-level folder that holds the
# repository's files (linked), build/ (the build under test) and ../shared beside it. Every ```sh block
# runs, except one right after a line
#     <!-- readme-test: not run: REASON -->
# (the test prints it with its reason). A failing command fails the test, naming its README line.
# Then the figures the README states for these runs are checked on the files the blocks wrote.
#   readme_blocks.sh REPO BUILD_DIR SHARED_DIR WORK_DIR
set -euo pipefail
[ $# -eq 4 ] || { echo "usage: $0 REPO BUILD_DIR SHARED_DIR WORK_DIR" >&2; exit 2; }
repo=$1 build=$2 shared=$3 work=$4
source "$(dirname "$0")/scratch_top.sh"
readme=$repo/README.md
scratch_top "$repo" "$build" "$shared" "$work"

# ---- the blocks -------------------------------------------------------------------------------------
# blocks/NNN-LINE.sh for each block that runs; skipped.txt "LINE: REASON" for the others
mkdir -p "$work/blocks"
awk -v dir="$work/blocks" -v skipped="$work/blocks/skipped.txt" '
  /^<!-- readme-test: not run: / { reason = $0; sub(/^<!-- readme-test: not run: /, "", reason); sub(/ -->$/, "", reason); next }
  !inside && /^```sh$/ {
    inside = 1; n++; start = NR + 1
    if (reason != "") { skip = 1; print start ": " reason > skipped }
    else { skip = 0; file = sprintf("%s/%03d-%d.sh", dir, n, start) }
    reason = ""; next
  }
  inside && /^```$/ { inside = 0; next }
  inside { if (!skip) print > file; next }
  /[^ ]/ { reason = "" }
' "$readme"
touch "$work/blocks/skipped.txt"
blocks=("$work"/blocks/[0-9]*.sh)
[ -e "${blocks[0]}" ] || { echo "readme: README.md: no command block to run" >&2; exit 1; }
while read -r line; do echo "readme: README.md:$line (not run)"; done < "$work/blocks/skipped.txt"

# one shell for all blocks, as a user pastes them one after the other
{
  echo 'set -eEo pipefail'
  echo 'trap '\''echo "readme: README.md:$((readme_line + LINENO - block_start)): failed: $BASH_COMMAND" >&2'\'' ERR'
  for b in "${blocks[@]}"; do
    line=${b##*-}; line=${line%.sh}
    echo "echo '== README.md:$line' >&2"
    echo "readme_line=$line; block_start=\$((LINENO + 1))"
    cat "$b"
  done
} > "$work/blocks/all.sh"
bash "$work/blocks/all.sh" 2>&1 | tee "$work/blocks/all.log"

# ---- what the README says these runs give ---------------------------------------------------------
fail() { echo "readme: $*" >&2; exit 1; }
records() { grep -vc '^#' "$1"; }
header() { awk -v k="# $1:" 'index($0, k) == 1 { print $3; exit }' "$2"; }
within() { awk -v v="$1" -v lo="$2" -v hi="$3" 'BEGIN { exit !(v >= lo && v <= hi) }'; }
n=$(records triplet.tracks)
within "$n" 7400 8000 || fail "triplet.tracks: $n triplets, the README says about 7700"
rmse=$(header rmse_px fit-ml.eval)
within "$rmse" 0.09 0.12 || fail "fit-ml.eval: rmse $rmse px, the README says about 0.11 px"
grep -q '^# verdict: accepted' ab.homography || fail "ab.homography: not accepted"
for p in 1-2 1-3 2-3; do
  back=from-colmap/img_0${p%-*}__img_0${p#*-}.matches
  [ -f "$back" ] && [ "$(records "$back")" = "$(records "pair-$p.matches")" ] ||
    fail "$back: not the records of pair-$p.matches"
done
# "RMS 0.563 px before, 0.0978 px after --model affine"
read -r before after < <(sed -n 's/^rpc-adjust: .*model affine: rms \([0-9.]*\) px before, \([0-9.]*\) px after.*/\1 \2/p' "$work/blocks/all.log")
within "${before:-0}" 0.55 0.58 && within "${after:-0}" 0.095 0.105 ||
  fail "rpc-adjust: rms ${before:-?} px before, ${after:-?} px after; the README says 0.563 and 0.0978"
n=$(records marseille.points)
within "$n" 7400 8000 || fail "marseille.points: $n ground points for the 7687 inlier tracks of the README"
# "A block of many images": tracks of 2 to 6 views, every image adjusted, ground points for every track
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]* 5:[0-9]* 6:' block-run/tracks.tracks ||
  fail "block-run/tracks.tracks: $(grep '^# tracks_by_views' block-run/tracks.tracks), the README shows tracks of 2 to 6 views"
rms=$(header rms_after_unflagged_px block-run/adjusted/rpc.residuals)
within "$rms" 0 0.06 || fail "block-run: rpc-adjust rms after $rms px, above the 0.06 px of a block adjusted to its tie points"
[ "$(records block-run/ground.points)" = "$(records block-run/tracks.tracks)" ] || fail "block-run/ground.points: not a point per track"
# "From tie points to the ground": check points within 0.5 m, the DEM-held block aligned with a median dz of 0
ce=$(header check_after_rmse_h_m gcp-adjusted/accuracy) cv=$(header check_after_rmse_v_m gcp-adjusted/accuracy)
within "$ce" 0 0.5 && within "$cv" 0 0.5 ||
  fail "gcp-adjusted/accuracy: check points at ${ce:-?} m horizontal, ${cv:-?} m vertical RMSE, the README says 0.24 and 0.17 m"
grep -q '^# shift_enu_m: ' hill.dz || fail "hill.dz: no shift_enu_m line"
dz=$(sed -n 's/^tp-ground: after alignment, dz all: .* dz median \([-0-9.e]*\) m.*/\1/p' "$work/blocks/all.log" | head -n 1)
within "${dz:-9}" -0.5 0.5 || fail "tp-ground --align: median dz ${dz:-?} m after alignment, the README says 0"
echo "readme: ${#blocks[@]} blocks ran; $(wc -l < "$work/blocks/skipped.txt") not run; figures as stated"
