#!/usr/bin/env bash
# Wall time and verified matches per pair: tp-match on the three pairs + tp-chain, against COLMAP 3.8
# (tp-match once per pair sharing a keypoint cache, and once for all three pairs)
# (CPU SIFT extraction + exhaustive matching with geometric verification), both with 2 threads, on
# the Pléiades triplet. COLMAP finds no features in the 16-bit files, so it gets the same 8-bit
# rendering tp-match's detector sees (bench_match_accuracy --render8: 0.5/99.5 percentile stretch).
#
#   bench/match_speed_colmap.sh [BUILD_DIR] [DATA_DIR] [WORK_DIR]
#
# ROUNDS=N (default 5): the three measurements run N times in turn, each round from an empty keypoint
# cache and database, and the ratios are taken within each round (a shared VM's speed drifts by tens
# of percent over a minute, so ratios of separate medians would mix different machines); the median
# round ratio is the figure.
#
# COLMAP is a benchmark peer only: it is installed here (apt-get, needs root and the network) when
# missing, never by the build or CI. Peak memory comes from /usr/bin/time -v.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${1:-$here/build}" && pwd)
data=$(cd "${2:-$here/../shared/data/pleiades-marseille}" && pwd)
work=${3:-$(mktemp -d /tmp/tpkit-colmap.XXXXXX)}
threads=2
bin=$build/bin
for t in tp-match tp-chain bench_match_accuracy; do
  [ -x "$bin/$t" ] || { echo "missing $bin/$t: build with -DTPKIT_BENCH=ON first" >&2; exit 1; }
done
if ! command -v colmap >/dev/null; then
  echo "installing colmap (Debian package, benchmark peer only)" >&2
  if [ "$(id -u)" = 0 ]; then apt-get install -y colmap; else sudo apt-get install -y colmap; fi
fi
export QT_QPA_PLATFORM=offscreen
mkdir -p "$work/images" "$work/tp"
cd "$work"
for i in 1 2 3; do "$bin/bench_match_accuracy" --render8 "$data/img_0$i.tif" "images/img_0$i.png"; done

timed() {  # label, command...: prints wall seconds and peak RSS
  local label=$1; shift
  /usr/bin/time -v "$@" 2> "$label.time" >/dev/null || { cat "$label.time" >&2; exit 1; }
  local wall rss
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, a, ":"); s = 0; for (i = 1; i <= n; ++i) s = s * 60 + a[i]; print s}' "$label.time")
  rss=$(awk -F': ' '/Maximum resident/ {print $2}' "$label.time")
  echo "$label $wall $rss"
}

echo "== tpkit (threads $threads) and COLMAP $(colmap -h 2>&1 | head -1 | awk '{print $2}') (threads $threads, CPU)"
rounds=${ROUNDS:-5}
ratios3=() ratios1=()
for round in $(seq 1 "$rounds"); do
  rm -rf tp tp1 colmap.db
  mkdir -p tp
  tp_total=0
  for p in "1 2" "1 3" "2 3"; do
    set -- $p
    r=$(timed "tp-match-$1$2" "$bin/tp-match" "$data/img_0$1.tif" "$data/img_0$2.tif" --threads $threads --cache tp/keypoints -q -o "tp/$1$2.matches")
    [ "$round" = 1 ] && echo "$r" | awk '{printf "tp-match %s: %.2f s, peak RSS %d MB\n", $1, $2, $3 / 1024}'
    tp_total=$(echo "$tp_total $(echo "$r" | awk '{print $2}')" | awk '{print $1 + $2}')
  done
  r=$(timed tp-chain "$bin/tp-chain" tp/12.matches tp/13.matches tp/23.matches -q -o tp/triplets.tracks)
  tp_total=$(echo "$tp_total $(echo "$r" | awk '{print $2}')" | awk '{print $1 + $2}')

  r=$(timed tp-match-all "$bin/tp-match" "$data/img_01.tif" "$data/img_02.tif" "$data/img_03.tif" --threads $threads -q -o tp1)
  [ "$round" = 1 ] && echo "$r" | awk '{printf "tp-match (every pair, one run): %.2f s, peak RSS %d MB\n", $2, $3 / 1024}'
  one_total=$(echo "$r" | awk '{print $2}')
  r=$(timed tp-chain1 "$bin/tp-chain" tp1/pair-1-2.matches tp1/pair-1-3.matches tp1/pair-2-3.matches -q -o tp1/triplets.tracks)
  one_total=$(echo "$one_total $(echo "$r" | awk '{print $2}')" | awk '{print $1 + $2}')

  r1=$(timed colmap-extract colmap feature_extractor --database_path colmap.db --image_path images \
    --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads $threads)
  r2=$(timed colmap-match colmap exhaustive_matcher --database_path colmap.db \
    --SiftMatching.use_gpu 0 --SiftMatching.num_threads $threads)
  colmap_total=$(echo "$r1 $r2" | awk '{print $2 + $5}')
  if [ "$round" = 1 ]; then
    echo "$r1" | awk '{printf "colmap feature_extractor: %.2f s, peak RSS %d MB\n", $2, $3 / 1024}'
    echo "$r2" | awk '{printf "colmap exhaustive_matcher: %.2f s, peak RSS %d MB\n", $2, $3 / 1024}'
    for p in 12 13 23; do
      echo "tp-match pair $p (three runs): $(grep -m1 '^# verified:' tp/$p.matches | awk '{print $3}') verified, $(grep -vc '^#' tp/$p.matches) refined"
    done
    for p in 1-2 1-3 2-3; do
      echo "tp-match pair $p (one run): $(grep -m1 '^# verified:' tp1/pair-$p.matches | awk '{print $3}') verified, $(grep -vc '^#' tp1/pair-$p.matches) refined"
    done
    echo "tp-chain: $(grep -vc '^#' tp/triplets.tracks) triplets (three runs), $(grep -vc '^#' tp1/triplets.tracks) (one run)"
    # pair_id = image_id1 * 2147483647 + image_id2 (COLMAP's encoding, image_id1 < image_id2)
    sqlite3 colmap.db "select image_id, rows from keypoints order by image_id;" | awk -F'|' '{print "colmap keypoints image " $1 ": " $2}'
    sqlite3 colmap.db "select pair_id, rows from two_view_geometries order by pair_id;" |
      awk -F'|' '{id2 = $1 % 2147483647; id1 = ($1 - id2) / 2147483647; print "colmap pair " id1 id2 ": " $2 " verified"}'
  fi
  ratio3=$(awk -v a="$tp_total" -v b="$colmap_total" 'BEGIN {printf "%.3f", a / b}')
  ratio1=$(awk -v a="$one_total" -v b="$colmap_total" 'BEGIN {printf "%.3f", a / b}')
  ratios3+=("$ratio3") ratios1+=("$ratio1")
  echo "round $round: tpkit three runs $tp_total s, one run $one_total s; COLMAP $colmap_total s; ratio three runs $ratio3, one run $ratio1"
done
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
echo "median ratio tpkit / COLMAP wall time over $rounds rounds: three runs $(median "${ratios3[@]}"), one run $(median "${ratios1[@]}") (issue 28 asks <= 0.25)"
echo "work folder: $work"
