#!/bin/bash
# A tiled tp-match run through a real scheduler, checked against a single-process run.
#   scale_out_engine.sh ENGINE BIN      ENGINE: slurm | parallel | make; BIN: the folder of the tools
# Makes a tp-synth scene (3 views) whose RPCs of views 2 and 3 carry an injected bias (--rpc-bias),
# plans it (tp-plan: 3 pairs x 4 regions, then tp-refine, rpc-adjust with view 1 fixed and tp-ground), runs the
# plan with the engine, and compares it with single-process runs:
# - tracks: with those of whole-pair tp-match runs chained by tp-chain as the plan chains them: at least
#   98% of the single-process tracks must come out of the tiled run with the same keypoint id and the
#   same positions within 0.01 px, and the tiled run may not invent more than 2% others (the scene's
#   relief gets the quadratic window model, which bends along each run's own epipolar geometry: a
#   region's differs from the whole pair's in the last digits, and so do the positions, by 1e-4 px
#   typically; with the affine model they are the same to the last digit);
# - refinement and adjustment: tp-refine, rpc-adjust and tp-ground run in one process each, with the plan's
#   options, on the plan's tracks give byte-identical refined tracks (the records), adjusted models (every
#   NAME_rpc.txt and NAME.RPB), rpc.bias and ground points (the records; the header names other model
#   files); and the whole single-process pipeline (whole-pair tp-match, tp-chain, tp-refine, rpc-adjust)
#   gives models that project the plan's ground points to
#   the same pixels within 0.01 px (its tracks differ from the tiled run's by a few: the coefficients
#   cannot agree to the last digit; measured: 7e-4 px with one track of 2911 missing);
# - the adjustment does something: the injected shifts of views 2 and 3 are recovered within 0.5 px.
# slurm: starts munged, slurmctld and slurmd on localhost (configuration written here, state in the
# scratch folder, free ports), submits the job arrays and waits; every daemon is stopped on exit,
# also on failure. A missing program is a failure, never a skip.
set -euo pipefail
engine=$1
BIN=$(cd "$2" && pwd)
# a space in every path on purpose; for Slurm also a '%j', which sbatch would expand in --output (each job
# then writing its log into a folder that does not exist, and failing) unless submit-slurm.sh writes %%
if [ "$engine" = slurm ]; then T=$(mktemp -d "${TMPDIR:-/tmp}/tpkit scale %j out.XXXXXX"); else T=$(mktemp -d "${TMPDIR:-/tmp}/tpkit scale out.XXXXXX"); fi
pids=()
S=
cleanup() {
  local rc=$?
  if [ $rc -ne 0 ]; then
    for f in "$S"/*.log "$T"/work/logs/*; do [ -f "$f" ] && { echo "== $f"; tail -20 "$f"; }; done
  fi
  stop_daemons
  rm -rf "$T"
  exit $rc
}
trap cleanup EXIT
trap 'exit 1' INT TERM
# shellcheck source=slurm_single_node.sh
source "$(dirname "${BASH_SOURCE[0]}")/slurm_single_node.sh"
need() { command -v "$1" >/dev/null || { echo "FAIL: $1 is not installed (scripts/install-deps.sh --test)" >&2; exit 1; }; }

run_plan() {
  case "$engine" in
    slurm)
      start_slurm
      timeout 240 bash "$T/work/submit-slurm.sh" --wait
      # every job of every stage ran and succeeded
      local n
      n=$(ls "$T/work/logs" | wc -l)
      echo "slurm: $n job logs"
      local jobs
      jobs=$(cat "$T"/work/jobs/{geometry,detect,tiles,merge,chain,refine,adjust,ground}.jobs | wc -l)
      [ "$n" -eq "$jobs" ] || { echo "FAIL: $n job logs in $T/work/logs for $jobs jobs" >&2; exit 1; }
      ;;
    parallel)
      need parallel
      timeout 240 bash "$T/work/run-parallel.sh" -j 2
      ;;
    make)
      need make
      timeout 240 make -s -C "$T/work" -f plan.mk -j 2
      ;;
    *) echo "unknown engine $engine" >&2; exit 2 ;;
  esac
}

# biases (truth pixel = written RPC projection + bias): view 2 a shift and a drift, view 3 a shift and
# affine terms; view 1, unbiased, is the plan's --fixed image
"$BIN/tp-synth" --out "$T/scene" --size 1024 --seed 5 --threads 2 --rpc-bias 2:6,-8,0.002,-0.001 --rpc-bias 3:-10,4,0,0,0.001,-0.002 >/dev/null 2>&1
mkdir -p "$T/images"
for k in 1 2 3; do cp "$T/scene/view$k.tif" "$T/images/view $k.tif"; done
V=("$T/images/view 1.tif" "$T/images/view 2.tif" "$T/images/view 3.tif")
# the single-process reference, with the plan's detection tile (--detect-tile: ids depend on it)
mkdir -p "$T/whole"
"$BIN/tp-match" -q --threads 2 --tile 512 "${V[0]}" "${V[1]}" -o "$T/whole/12.matches"
"$BIN/tp-match" -q --threads 2 --tile 512 "${V[0]}" "${V[2]}" -o "$T/whole/13.matches"
"$BIN/tp-match" -q --threads 2 --tile 512 "${V[1]}" "${V[2]}" -o "$T/whole/23.matches"
"$BIN/tp-chain" -q --unrefined --rpc-check 1 --images "${V[@]}" -o "$T/whole.tracks" "$T/whole/12.matches" "$T/whole/13.matches" "$T/whole/23.matches"
"$BIN/tp-refine" -q "${V[@]}" --tracks "$T/whole.tracks" --threads 1 -o "$T/whole-refined.tracks"
ADJUST=(--model affine --fixed "${V[0]}" --threads 1 --loss 0.5)
"$BIN/rpc-adjust" "${V[@]}" --tracks "$T/whole-refined.tracks" "${ADJUST[@]}" -o "$T/whole-adjusted" 2>/dev/null

"$BIN/tp-plan" -q -o "$T/work" --tile 512 --detect-tile 512 --bin "$BIN" --adjust-model affine --fixed "${V[0]}" \
  --adjust-options "--loss 0.5" "${V[@]}"
[ "$(wc -l < "$T/work/jobs/tiles.jobs")" -eq 12 ] || { echo "FAIL: expected 12 region jobs" >&2; exit 1; }
[ "$(wc -l < "$T/work/jobs/detect.jobs")" -eq 6 ] || { echo "FAIL: expected 6 detection jobs (3 images x 2 rows of regions)" >&2; exit 1; }
run_plan
[ -s "$T/work/tracks.tracks" ] || { echo "FAIL: the $engine run wrote no tracks" >&2; exit 1; }
for p in pair-1-2 pair-1-3 pair-2-3; do
  [ "$(ls "$T/work/tiles/$p" | wc -l)" -eq 4 ] || { echo "FAIL: $p lacks region files" >&2; exit 1; }
  [ -s "$T/work/pairs/$p.matches" ] || { echo "FAIL: $p was not merged" >&2; exit 1; }
done

# every detection tile was detected once, by the detect stage: each tile is in one report, none was
# found in the cache there, and the region jobs added no cache entry (they read them all)
reports=$(cat "$T"/work/detect/image-*/*.detection | grep -vc '^#')
detected=$(cat "$T"/work/detect/image-*/*.detection | awk '!/^#/ && $7 == 0' | wc -l)
entries=$(find "$T/work/cache" -name '*.sift' | wc -l)
echo "$engine: $reports detection tiles in the reports, $detected detected, $entries cache entries"
[ "$reports" -gt 0 ] && [ "$reports" -eq "$detected" ] && [ "$entries" -eq "$reports" ] ||
  { echo "FAIL: detection tiles not detected exactly once by the detect stage" >&2; exit 1; }

# compare: tracks by reference keypoint (columns kp and ref, found by name in the header), positions
# (x1 y1 .. y3) within 0.01 px
awk -v engine="$engine" '
  FNR == 1 { f++ }
  /^# columns:/ { for (i = 3; i <= NF; i++) col[$i] = i - 2; next }
  /^#/ { next }
  { key = $col["kp"] " " $col["ref"] }
  f == 1 { w[key] = $0; nw++; next }
  f == 2 { nt++; if (key in w) { split(w[key], a); same = 1
             for (v = 1; v <= 3; v++) for (c = 0; c <= 1; c++) {
               i = col[(c ? "y" : "x") v]; d = a[i] - $i; if (d < 0) d = -d; if (d > 1e-2) same = 0 }
             if (same) ns++ } }
  END {
    printf "%s: whole-run tracks %d, tiled %d, identical %d (%.2f%%)\n", engine, nw, nt, ns, 100 * ns / nw
    if (nw < 500) { print "FAIL: too few whole-run tracks"; exit 1 }
    if (ns < 0.98 * nw) { print "FAIL: fewer than 98% of the whole-run tracks"; exit 1 }
    if (nt > 1.02 * nw) { print "FAIL: more than 2% extra tracks"; exit 1 }
  }' "$T/whole.tracks" "$T/work/tracks.tracks"

# the refinement and the adjustment: WORK/refined.tracks, WORK/adjusted and WORK/ground.points are there,
# made after the chain, in that order
[ -s "$T/work/refined.tracks" ] && [ -s "$T/work/adjusted/rpc.bias" ] && [ -s "$T/work/ground.points" ] || { echo "FAIL: the $engine run did not refine and adjust" >&2; exit 1; }
[ ! "$T/work/tracks.tracks" -nt "$T/work/refined.tracks" ] && [ ! "$T/work/refined.tracks" -nt "$T/work/adjusted/rpc.bias" ] &&
  [ ! "$T/work/adjusted/rpc.bias" -nt "$T/work/ground.points" ] ||
  { echo "FAIL: the $engine run did not run chain, refine, adjust, ground in that order" >&2; exit 1; }
# the same in one process each, on the plan's tracks: byte-identical
"$BIN/tp-refine" -q "${V[@]}" --tracks "$T/work/tracks.tracks" --threads 1 -o "$T/one-refined.tracks"
cmp <(grep -v '^#' "$T/one-refined.tracks") <(grep -v '^#' "$T/work/refined.tracks") ||
  { echo "FAIL: $engine: refined.tracks differs from the one-process tp-refine's" >&2; exit 1; }
"$BIN/rpc-adjust" "${V[@]}" --tracks "$T/work/refined.tracks" "${ADJUST[@]}" -o "$T/one-adjusted" 2>/dev/null
rpcs=()
for v in "${V[@]}"; do rpcs+=(--rpc "$v=$T/one-adjusted/$(basename "${v%.*}")_rpc.txt"); done
"$BIN/tp-ground" "${V[@]}" --tracks "$T/work/refined.tracks" "${rpcs[@]}" --threads 1 -o "$T/one.points" 2>/dev/null
identical=0
for k in 1 2 3; do
  for f in "view ${k}_rpc.txt" "view $k.RPB"; do
    cmp "$T/one-adjusted/$f" "$T/work/adjusted/$f" || { echo "FAIL: $engine: adjusted/$f differs from the one-process rpc-adjust's" >&2; exit 1; }
    identical=$((identical + 1))
  done
done
cmp "$T/one-adjusted/rpc.bias" "$T/work/adjusted/rpc.bias" || { echo "FAIL: $engine: rpc.bias differs" >&2; exit 1; }
cmp <(grep -v '^#' "$T/one.points") <(grep -v '^#' "$T/work/ground.points") ||
  { echo "FAIL: $engine: ground.points differs from the one-process tp-ground's" >&2; exit 1; }
points=$(grep -vc '^#' "$T/work/ground.points")
echo "$engine: refined tracks, $identical adjusted model files and rpc.bias byte-identical to one-process tp-refine and rpc-adjust; $points ground points identical"
# against the whole single-process pipeline: the plan's ground points projected through both models
grep -v '^#' "$T/work/ground.points" | awk '{ print $2, $3, $4 }' > "$T/ground.lonlath"
worst=0
for k in 1 2 3; do
  d=$(paste <("$BIN/tp-rpc" project "$T/work/adjusted/view ${k}_rpc.txt" -q -i "$T/ground.lonlath" | grep -v '^#') \
            <("$BIN/tp-rpc" project "$T/whole-adjusted/view ${k}_rpc.txt" -q -i "$T/ground.lonlath" | grep -v '^#') |
      awk '{ for (i = 1; i <= 2; i++) { e = $i - $(i + 3); if (e < 0) e = -e; if (e > m) m = e } } END { printf "%.3g", m }')
  worst=$(awk -v a="$worst" -v b="$d" 'BEGIN { print (b > a ? b : a) }')
done
echo "$engine: adjusted models against the whole single-process pipeline: largest difference $worst px over $points ground points"
awk -v w="$worst" 'BEGIN { exit !(w <= 0.01) }' || { echo "FAIL: $engine: the adjusted models differ from the single-process run's by $worst px" >&2; exit 1; }
# the injected shifts recovered (columns image a0 a1 a2 b0 b1 b2; truth.bias the same)
awk 'FNR == 1 { f++ } /^#/ { next } f == 1 { t[$1] = $2; next }
  $1 > 1 { d = $2 - t[$1]; if (d < 0) d = -d; printf "view %d: a0 %.3f px, injected %g\n", $1, $2, t[$1]; if (d > 0.5) bad = 1 }
  END { if (bad) { print "FAIL: the injected shifts were not recovered"; exit 1 } }' "$T/scene/truth.bias" "$T/work/adjusted/rpc.bias"
echo "PASS: $engine"
