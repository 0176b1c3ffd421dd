#!/bin/bash
# Scale-out benchmark (issue 16): a tp-synth pair split into 16 regions and run as a Slurm job array on
# a single-node Slurm started here (tests/tools/slurm_single_node.sh), against the whole-pair run.
#   bench/scale_out.sh BIN SCENE10K [SCENE2]   (SCENE2: a scene of another size, e.g. 20000 or 5000)
# BIN: folder of the tools; SCENEnK: tp-synth folders (view1.tif, view2.tif), e.g.
#   tp-synth --out s10k --size 10000 --seed 1 --supersample 1
# Prints: the whole run's wall / CPU time and peak memory; per region job peak memory (max) and CPU
# time; total CPU of geometry + regions + merge against the whole run's; the array's wall time; the
# share of the whole run's matches found with the same ids and positions (1e-6 px); and one job's
# memory and time for regions of 2000 and 4000 pixels in each scene given.
# Every job runs with one thread (--threads 1; the whole run with 2, its CPU time is what compares).
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
for t in tp-match tp-merge tp-chain; do
  cat > "$T/timed/$t" <<WRAP
#!/bin/bash
exec /usr/bin/time -f "$t %e %U %S %M" -o "$T/times/\$(date +%s%N).\$\$" "$BIN/$t" "\$@"
WRAP
  chmod +x "$T/timed/$t"
done
timed() {  # LABEL CMD...: runs CMD under /usr/bin/time, prints "LABEL wall user sys maxrss"
  local label=$1; shift
  /usr/bin/time -f "$label %e %U %S %M" -o "$T/one.time" "$@" >/dev/null 2>&1
  cat "$T/one.time"
}

V1=$S10/view1.tif
V2=$S10/view2.tif
echo "== whole run (tp-match --threads 2) of $V1 and $V2"
if [ -n "${WHOLE_MATCHES:-}" ]; then
  cp "$WHOLE_MATCHES" "$T/whole.matches"
  echo "whole (from WHOLE_MATCHES, WHOLE_TIME: wall user sys maxrss_kB) ${WHOLE_TIME:-unknown}"
  read -r _ ww wu wsys wrss <<< "whole ${WHOLE_TIME:-0 0 0 0}"
else
  read -r _ ww wu wsys wrss < <(timed whole "$BIN/tp-match" --threads 2 -q "$V1" "$V2" -o "$T/whole.matches")
  echo "whole wall ${ww} s, cpu $(awk -v a="$wu" -v b="$wsys" "BEGIN { print a + b }") s, peak ${wrss} kB"
fi

echo "== 16 regions through a Slurm job array"
width=$(awk '/^# image1:/ { print $(NF - 1); exit }' "$T/whole.matches")
tile=$(( (width + 3) / 4 ))
"$BIN/tp-plan" -q -o "$T/work" --tile "$tile" --threads 1 --bin "$T/timed" "$V1" "$V2"
echo "regions: $(wc -l < "$T/work/jobs/tiles.jobs") of ${tile} px"
start_slurm
t0=$(date +%s.%N)
bash "$T/work/submit-slurm.sh" --wait >/dev/null
t1=$(date +%s.%N)
echo "slurm array wall (geometry, 16 regions, merge, chain; 2 jobs at a time): $(awk -v a="$t0" -v b="$t1" "BEGIN { printf \"%.1f\", b - a }") s"
cat "$T"/times/* > "$T/all.times"
awk -v wu="$wu" -v ws="$wsys" '
  { cpu = $3 + $4; total += cpu; if ($1 == "tp-match" && cpu > 0) { n[$1]++ } }
  $1 == "tp-match" { if ($5 > rss) rss = $5; jobs++; if (cpu > maxcpu) maxcpu = cpu; if (cpu < mincpu || mincpu == 0) mincpu = cpu }
  END {
    printf "tp-match jobs %d (geometry + regions): peak memory max %.0f MB, cpu per job %.1f..%.1f s\n", jobs, rss / 1024, mincpu, maxcpu
    printf "total cpu of the tiled run %.1f s, whole run %.1f s: %+.1f%%\n", total, wu + ws, 100 * (total / (wu + ws) - 1)
  }' "$T/all.times"
awk 'FNR == 1 { f++ } /^#/ { next }
  f == 1 { w[$1 " " $4] = $2 " " $3 " " $5 " " $6; n++; next }
  { m++; k = $1 " " $4; if (k in w) { split(w[k], a); d = 0
      for (i = 1; i <= 4; i++) { v = a[i] - $(i < 3 ? i + 1 : i + 2); if (v < 0) v = -v; if (v > d) d = v }
      if (d <= 1e-6) s++ } }
  END { printf "whole-run matches %d, tiled %d, same ids and positions %d (%.2f%%)\n", n, m, s, 100 * s / n }' \
  "$T/whole.matches" "$T/work/pairs/pair-1-2.matches"

echo "== one region job (--threads 1) by region size and scene size"
for scene in "$S10" ${S20:+"$S20"}; do
  g="$T/$(basename "$scene").geometry"
  timed "geometry $(basename "$scene")" "$BIN/tp-match" -q --threads 1 --write-geometry "$g" "$scene/view1.tif" "$scene/view2.tif"
  w=$(awk '/^# image1:/ { print $(NF - 1); exit }' "$g")
  for r in 2000 4000; do
    x=$(( (w - r) / 2 ))
    timed "region ${r} in $(basename "$scene") (${w} px)" "$BIN/tp-match" -q --threads 1 --geometry "$g" --region "$x" "$x" "$r" "$r" \
      "$scene/view1.tif" "$scene/view2.tif" -o "$T/r.matches"
  done
done | awk '{ rss = $NF; sys = $(NF - 1); usr = $(NF - 2); wall = $(NF - 3); NF -= 4; printf "%s: wall %.1f s, cpu %.1f s, peak %.0f MB\n", $0, wall, usr + sys, rss / 1024 }'
