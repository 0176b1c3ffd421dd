#!/bin/bash
# Scale-out benchmark (issue 16): a tp-synth pair split into 16 regions and run as a Slurm job array on
# a single-node Slurm started here (tests/tools/slurm_single_node.sh), against the whole-pair run.
#   bench/scale_out.sh BIN SCENE10K [SCENE2]   (SCENE2: a scene of another size, e.g. 20000 or 5000)
# BIN: folder of the tools; SCENEnK: tp-synth folders (view1.tif, view2.tif), e.g.
#   tp-synth --out s10k --size 10000 --seed 1 --supersample 1
# Prints: the whole run's wall / CPU time and peak memory, with the plan's detection tile (tp-plan
# --detect-tile, default 768: keypoint ids depend on it) and with tp-match's default (1024); per job
# of the plan (geometry, detection, regions, and the merge, chain, rpc-adjust and tp-ground jobs) peak
# memory and CPU time; CPU of the matching jobs (geometry, detection, regions, tp-merge) against the whole
# tp-match run's (the mean of a run before the plan and one after it), and of the jobs after them; the array's wall time; the share of the whole run's matches found with the same ids
# and positions (1e-6 px); and for regions of 2000 and 4000 pixels in each scene given, the memory and
# time of a detection job on such a block, of a region job that detects its own tiles, and of the same
# region job once the cache holds them (as in a plan); these with --no-rpc, so that a scene with RPC
# sidecars (tp-synth writes them) is searched as one without.
# Every job runs with one thread (--threads 1; the whole run with 2, its CPU time is what compares).
# DETECT_TILE (default 768) sets the detection tile; WHOLE_MATCHES and WHOLE_TIME ("wall user sys
# maxrss_kB") reuse a whole run made with it; SKIP_DEFAULT_TILE=1 skips the run at 1024.
set -euo pipefail
BIN=$(cd "$1" && pwd)
S10=$(cd "$2" && pwd)
S20=${3:+$(cd "$3" && pwd)}
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
T=$(mktemp -d "${TMPDIR:-/tmp}/tpkit-scale-out.XXXXXX")
pids=()
S=
cleanup() {
  stop_daemons
  rm -rf "$T"
}
trap cleanup EXIT
trap 'exit 1' INT TERM
source "$HERE/../tests/tools/slurm_single_node.sh"
command -v /usr/bin/time >/dev/null || { echo "needs /usr/bin/time (Debian package time)" >&2; exit 1; }

# wrappers that time every tool run of the plan: one line "tool wall user sys maxrss_kB" per run
mkdir -p "$T/timed" "$T/times"
for t in tp-match tp-merge tp-chain rpc-adjust tp-ground; do
  cat > "$T/timed/$t" <<WRAP
#!/bin/bash
exec /usr/bin/time -f "$t %e %U %S %M %C" -o "$T/times/\$(date +%s%N).\$\$" "$BIN/$t" "\$@"
WRAP
  chmod +x "$T/timed/$t"
done
timed() {  # LABEL CMD...: runs CMD under /usr/bin/time, prints "LABEL wall user sys maxrss"
  local label=$1; shift
  /usr/bin/time -f "$label %e %U %S %M" -o "$T/one.time" "$@" >/dev/null 2>&1
  cat "$T/one.time"
}

DT=${DETECT_TILE:-768}
V1=$S10/view1.tif
V2=$S10/view2.tif
echo "== whole run (tp-match --threads 2 --tile $DT) of $V1 and $V2"
if [ -n "${WHOLE_MATCHES:-}" ]; then
  cp "$WHOLE_MATCHES" "$T/whole.matches"
  echo "whole (from WHOLE_MATCHES, WHOLE_TIME: wall user sys maxrss_kB) ${WHOLE_TIME:-unknown}"
  read -r _ ww wu wsys wrss <<< "whole ${WHOLE_TIME:-0 0 0 0}"
else
  read -r _ ww wu wsys wrss < <(timed whole "$BIN/tp-match" --threads 2 --tile "$DT" -q "$V1" "$V2" -o "$T/whole.matches")
fi
echo "whole, tile $DT: wall ${ww} s, cpu $(awk -v a="$wu" -v b="$wsys" "BEGIN { print a + b }") s, peak $(( wrss / 1024 )) MB"
if [ "${SKIP_DEFAULT_TILE:-0}" != 1 ]; then
  read -r _ dw du dsys drss < <(timed whole "$BIN/tp-match" --threads 2 -q "$V1" "$V2" -o "$T/whole-1024.matches")
  echo "whole, tile 1024 (tp-match's default): wall ${dw} s, cpu $(awk -v a="$du" -v b="$dsys" "BEGIN { print a + b }") s, peak $(( drss / 1024 )) MB"
  rm -f "$T/whole-1024.matches"
fi

echo "== 16 regions through a Slurm job array"
width=$(awk '/^# image1:/ { print $(NF - 1); exit }' "$T/whole.matches")
tile=$(( (width + 3) / 4 ))
"$BIN/tp-plan" -q -o "$T/work" --tile "$tile" --detect-tile "$DT" --threads 1 --bin "$T/timed" "$V1" "$V2"
echo "regions: $(wc -l < "$T/work/jobs/tiles.jobs") of ${tile} px; detection jobs: $(wc -l < "$T/work/jobs/detect.jobs")"
start_slurm
t0=$(date +%s.%N)
bash "$T/work/submit-slurm.sh" --wait >/dev/null
t1=$(date +%s.%N)
echo "slurm array wall (geometry, detection, 16 regions, merge, chain, adjust, ground; 2 jobs at a time): $(awk -v a="$t0" -v b="$t1" "BEGIN { printf \"%.1f\", b - a }") s"
cat "$T"/times/* > "$T/all.times"
# the whole run again, after the plan: this machine's speed drifts by 5-15% over minutes, so the plan is
# compared with the mean of a run before it and one after it (and each is printed)
wu2=$wu wsys2=$wsys
if [ -z "${WHOLE_MATCHES:-}" ]; then
  read -r _ ww2 wu2 wsys2 wrss2 < <(timed whole "$BIN/tp-match" --threads 2 --tile "$DT" -q "$V1" "$V2" -o "$T/whole-again.matches")
  echo "whole again, after the plan, tile $DT: wall ${ww2} s, cpu $(awk -v a="$wu2" -v b="$wsys2" "BEGIN { print a + b }") s, peak $(( wrss2 / 1024 )) MB"
  rm -f "$T/whole-again.matches"
fi
awk -v w1="$(awk -v a="$wu" -v b="$wsys" 'BEGIN { print a + b }')" -v w2="$(awk -v a="$wu2" -v b="$wsys2" 'BEGIN { print a + b }')" '
  { cpu = $3 + $4; total += cpu
    k = $1; if ($0 ~ /--write-geometry/) k = "geometry"; else if ($0 ~ /--detect/) k = "detect"; else if ($0 ~ /--region/) k = "region"
    n[k]++; c[k] += cpu; if ($5 > rss[k]) rss[k] = $5; if ($5 > peak) peak = $5; if (cpu > mx[k]) mx[k] = cpu }
  END {
    for (k in n) printf "%-9s jobs %3d: cpu %7.1f s (largest job %.1f s), peak memory %4.0f MB\n", k, n[k], c[k], mx[k], rss[k] / 1024
    printf "peak memory of any job %.0f MB\n", peak / 1024
    # the whole run is tp-match alone: it compares with the matching jobs of the plan; the jobs after them
    # (tp-chain, rpc-adjust, tp-ground) have no counterpart in it
    m = c["geometry"] + c["detect"] + c["region"] + c["tp-merge"]
    w = (w1 + w2) / 2
    printf "matching jobs (geometry, detection, regions, tp-merge) cpu %.1f s, whole tp-match run %.1f s (mean of %.1f before and %.1f after): %+.1f%%\n", m, w, w1, w2, 100 * (m / w - 1)
    printf "jobs after the matching (tp-chain, rpc-adjust, tp-ground) cpu %.1f s; every job %.1f s\n", total - m, total
  }' "$T/all.times"
awk 'FNR == 1 { f++ } /^#/ { next }
  f == 1 { w[$1 " " $4] = $2 " " $3 " " $5 " " $6; n++; next }
  { m++; k = $1 " " $4; if (k in w) { split(w[k], a); d = 0
      for (i = 1; i <= 4; i++) { v = a[i] - $(i < 3 ? i + 1 : i + 2); if (v < 0) v = -v; if (v > d) d = v }
      if (d <= 1e-6) s++ } }
  END { printf "whole-run matches %d, tiled %d, same ids and positions %d (%.2f%%)\n", n, m, s, 100 * s / n }' \
  "$T/whole.matches" "$T/work/pairs/pair-1-2.matches"

echo "== one job (--threads 1) by region size and scene size"
for scene in "$S10" ${S20:+"$S20"}; do
  g="$T/$(basename "$scene").geometry"
  timed "geometry $(basename "$scene")" "$BIN/tp-match" -q --threads 1 --tile "$DT" --write-geometry "$g" "$scene/view1.tif" "$scene/view2.tif"
  w=$(awk '/^# image1:/ { print $(NF - 1); exit }' "$g")
  for r in 2000 4000; do
    x=$(( (w - r) / 2 ))
    rm -rf "$T/c1" "$T/c2"
    timed "detection job, block ${r} in $(basename "$scene") (${w} px)" "$BIN/tp-match" -q --threads 1 --tile "$DT" --geometry "$g" \
      --detect 1 --region "$x" "$x" "$r" "$r" --cache "$T/c1" "$scene/view1.tif" "$scene/view2.tif" -o "$T/d.detection"
    timed "region job ${r}, detecting its tiles, in $(basename "$scene") (${w} px)" "$BIN/tp-match" -q --threads 1 --tile "$DT" \
      --no-rpc --geometry "$g" --region "$x" "$x" "$r" "$r" --cache "$T/c2" "$scene/view1.tif" "$scene/view2.tif" -o "$T/r.matches"
    timed "region job ${r}, keypoints from the cache, in $(basename "$scene") (${w} px)" "$BIN/tp-match" -q --threads 1 --tile "$DT" \
      --no-rpc --geometry "$g" --region "$x" "$x" "$r" "$r" --cache "$T/c2" "$scene/view1.tif" "$scene/view2.tif" -o "$T/r.matches"
  done
done | awk '{ rss = $NF; sys = $(NF - 1); usr = $(NF - 2); wall = $(NF - 3); NF -= 4; printf "%s: wall %.1f s, cpu %.1f s, peak %.0f MB\n", $0, wall, usr + sys, rss / 1024 }'
