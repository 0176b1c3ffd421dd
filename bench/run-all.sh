#!/usr/bin/env bash
# bench/run-all.sh: runs every benchmark with the arguments that print its issue's figures and writes
# bench/RESULTS.md: per benchmark, the exact command and what it printed. Figures are replaced, never
# appended: the git log keeps the earlier ones.
#   bash bench/run-all.sh [NAME...]     (default: all; NAME as listed by --list)
# With names, only those benchmarks run and only their sections of RESULTS.md are replaced; the others
# are kept as they are. Needs a Release build with the benchmarks in build/bin. Benchmarks run under
# nice -n 19: this machine may be shared, and the timings say so.
# bench_rpc_truth and bench_dem_reference are helpers of the scripts (block_adjust.sh, dem_align.sh),
# not benchmarks of their own.
set -euo pipefail
cd "$(dirname "$0")/.."
results=bench/RESULTS.md

# name | command, as a user types it in the repository root ($work: a scratch folder of its own)
benches=(
  "chain|build/bin/bench_chain"
  "rpc_adjust|build/bin/bench_rpc_adjust"
  "rpc_points|build/bin/bench_rpc_points"
  "cluster|build/bin/bench_cluster --section families && build/bin/bench_cluster --section unrelated --n 100 --trials 3000"
  "trifocal|build/bin/bench_trifocal --accuracy"
  "synth|build/bin/bench_synth --agreement"
  "match_accuracy|build/bin/tp-synth --out \$work/s --size 512 --seed 3 --relief 15 > /dev/null && build/bin/bench_match_accuracy --synth \$work/s --threads 2"
  "trifocal_real_table|sh bench/trifocal_real_table.sh build \$work"
  "gcp_accuracy|bash bench/gcp_accuracy.sh \$work"
  "dem_align|bash bench/dem_align.sh \$work"
  "ortho_gdalwarp|bash bench/ortho_gdalwarp.sh \$work"
  "ortho_alignment|bash bench/ortho_alignment.sh \$work"
  "block_adjust|bash bench/block_adjust.sh \$work"
  "block_blunders|bash bench/block_blunders.sh \$work"
  "match_speed_colmap|bash bench/match_speed_colmap.sh build ../shared/data/pleiades-marseille \$work"
  "dates_conditions|bash bench/dates_conditions.sh build \$work"
  "real_multidate|bash bench/real_multidate.sh build \$work"
  "scale_out|build/bin/tp-synth --out \$work/s10k --size 10000 --seed 1 --supersample 1 > /dev/null && bash bench/scale_out.sh build/bin \$work/s10k"
)
if [ "${1:-}" = --list ]; then for b in "${benches[@]}"; do echo "${b%%|*}"; done; exit 0; fi
if [ "${1:-}" = --help ] || [ "${1:-}" = -h ]; then sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; exit 0; fi
want=("$@")
for w in "${want[@]}"; do
  printf '%s\n' "${benches[@]}" | grep -q "^$w|" || { echo "run-all: $w: no such benchmark (--list)" >&2; exit 2; }
done

scratch=$(mktemp -d /tmp/tpkit-bench.XXXXXX)
trap 'rm -rf "$scratch"' EXIT
# a section of RESULTS.md: between '<!-- bench NAME -->' and '<!-- end NAME -->'
section() {  # NAME CMD: runs it, prints the section
  local name=$1 cmd=$2 work=$scratch/$1 start load status=0
  mkdir -p "$work"
  start=$(date +%s) load=$(cut -d' ' -f1 /proc/loadavg)
  echo "run-all: $name: $cmd" >&2
  # progress lines (carriage returns) are not figures
  (export work; nice -n 19 bash -c "set -o pipefail; $cmd" 2>&1 | tr '\r' '\n' | grep -v '^ *$' > "$work.out") || status=$?
  echo "<!-- bench $name -->"
  echo "## $name"
  echo
  echo "\`$cmd\`"
  echo
  # the load average at the start says how much of the machine the benchmark had (it runs under nice)
  echo "$(date -u +%Y-%m-%d), $(nproc) cores ($(uname -m)), load average $load at the start, $(( $(date +%s) - start )) s wall$([ "$status" = 0 ] || echo ", exit status $status")"
  echo
  echo '```text'
  cat "$work.out"
  echo '```'
  echo "<!-- end $name -->"
}
# the benchmarks run first, each into its own file; then, under a lock (two runs of different names may
# overlap), the sections they replace are put into the RESULTS.md of that moment
for b in "${benches[@]}"; do
  name=${b%%|*} cmd=${b#*|}
  if [ ${#want[@]} = 0 ] || printf '%s\n' "${want[@]}" | grep -qx "$name"; then section "$name" "$cmd" > "$scratch/$name.md"; fi
done
exec 9< bench
flock 9
old=$scratch/old.md
[ -f "$results" ] && cp "$results" "$old" || : > "$old"
new=$scratch/new.md
{
  echo "# Benchmark results"
  echo
  echo "Written by \`bash bench/run-all.sh\` (every benchmark; with names, only those sections are replaced):"
  echo "each section is one benchmark's command, run from the repository root on a Release build, and what"
  echo "it printed. Do not edit by hand. Timings are of the machine each section names."
  echo
  for b in "${benches[@]}"; do
    name=${b%%|*}
    if [ ! -f "$scratch/$name.md" ]; then
      awk -v s="<!-- bench $name -->" -v e="<!-- end $name -->" '$0 == s { on = 1 } on { print } $0 == e { on = 0 }' \
        "$old" > "$scratch/$name.md"
    fi
    # a benchmark never run has no section yet
    if [ -s "$scratch/$name.md" ]; then cat "$scratch/$name.md"; echo; fi
  done
} > "$new"
mv "$new" "$results"
echo "run-all: $results written" >&2
