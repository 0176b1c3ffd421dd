#!/bin/bash
# A tiled tp-match run through a real scheduler, checked against a single-process run.
#   scale_out_engine.sh ENGINE BIN      ENGINE: slurm | parallel | make; BIN: the folder of the tools
# Makes a tp-synth scene (3 views), plans it (tp-plan: 3 pairs x 4 regions), runs the plan with the
# engine, and compares the tracks with those of whole-pair tp-match runs chained by tp-chain: at least
# 98% of the single-process tracks must come out of the tiled run with the same keypoint id and the
# same positions (1e-6 px), and the tiled run may not invent more than 2% others.
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
      timeout 120 bash "$T/work/submit-slurm.sh" --wait
      # every job of every stage ran and succeeded
      local n
      n=$(ls "$T/work/logs" | wc -l)
      echo "slurm: $n job logs"
      local jobs
      jobs=$(cat "$T"/work/jobs/{geometry,detect,tiles,merge,chain}.jobs | wc -l)
      [ "$n" -eq "$jobs" ] || { echo "FAIL: $n job logs in $T/work/logs for $jobs jobs" >&2; exit 1; }
      ;;
    parallel)
      need parallel
      timeout 120 bash "$T/work/run-parallel.sh" -j 2
      ;;
    make)
      need make
      timeout 120 make -s -C "$T/work" -f plan.mk -j 2
      ;;
    *) echo "unknown engine $engine" >&2; exit 2 ;;
  esac
}

"$BIN/tp-synth" --out "$T/scene" --size 1024 --seed 5 --threads 2 >/dev/null 2>&1
mkdir -p "$T/images"
for k in 1 2 3; do cp "$T/scene/view$k.tif" "$T/images/view $k.tif"; done
V=("$T/images/view 1.tif" "$T/images/view 2.tif" "$T/images/view 3.tif")
# the single-process reference, with the plan's detection tile (--detect-tile: ids depend on it)
mkdir -p "$T/whole"
"$BIN/tp-match" -q --threads 2 --tile 512 "${V[0]}" "${V[1]}" -o "$T/whole/12.matches"
"$BIN/tp-match" -q --threads 2 --tile 512 "${V[0]}" "${V[2]}" -o "$T/whole/13.matches"
"$BIN/tp-match" -q --threads 2 --tile 512 "${V[1]}" "${V[2]}" -o "$T/whole/23.matches"
"$BIN/tp-chain" -q --images "${V[@]}" -o "$T/whole.tracks" "$T/whole/12.matches" "$T/whole/13.matches" "$T/whole/23.matches"

"$BIN/tp-plan" -q -o "$T/work" --tile 512 --detect-tile 512 --bin "$BIN" "${V[@]}"
[ "$(wc -l < "$T/work/jobs/tiles.jobs")" -eq 12 ] || { echo "FAIL: expected 12 region jobs" >&2; exit 1; }
[ "$(wc -l < "$T/work/jobs/detect.jobs")" -eq 12 ] || { echo "FAIL: expected 12 detection jobs (3 images x 4 blocks)" >&2; exit 1; }
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

# compare: tracks by reference keypoint id (last column), positions within 1e-6 px
awk -v engine="$engine" '
  FNR == 1 { f++ }
  /^#/ { next }
  f == 1 { w[$NF] = $0; nw++; next }
  f == 2 { nt++; if ($NF in w) { split(w[$NF], a); same = 1
             for (i = 2; i < NF; i++) { d = a[i] - $i; if (d < 0) d = -d; if (d > 1e-6) same = 0 }
             if (same) ns++ } }
  END {
    printf "%s: whole-run tracks %d, tiled %d, identical %d (%.2f%%)\n", engine, nw, nt, ns, 100 * ns / nw
    if (nw < 500) { print "FAIL: too few whole-run tracks"; exit 1 }
    if (ns < 0.98 * nw) { print "FAIL: fewer than 98% of the whole-run tracks"; exit 1 }
    if (nt > 1.02 * nw) { print "FAIL: more than 2% extra tracks"; exit 1 }
  }' "$T/whole.tracks" "$T/work/tracks.tracks"
echo "PASS: $engine"
