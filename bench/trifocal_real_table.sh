#!/bin/sh
# The paper's table on the real Pleiades triplet (issue 4): tie points by tp-match for the three pairs,
# tracks by tp-chain (three views), then bench_trifocal --real: RMSE (reproj-eval's definition) for
# 10, 100, 1000 fit tracks x every method, N random subsets per cell drawn with a fixed seed, fit tracks
# and held-out tracks reported separately.
#
#   bench/trifocal_real_table.sh BUILD_DIR [WORK_DIR] [TRIALS] [SEED]
#
# BUILD_DIR holds bin/tp-match, bin/tp-chain and bin/bench_trifocal (a Release build; the environment
# variables TP_MATCH, TP_CHAIN, BENCH_TRIFOCAL name other executables); WORK_DIR
# (default a temporary folder) keeps the matches and real.tracks. Data: ../shared/data/pleiades-marseille.
set -eu
build=${1:?usage: trifocal_real_table.sh BUILD_DIR [WORK_DIR] [TRIALS] [SEED]}
work=${2:-$(mktemp -d)}
trials=${3:-20}
seed=${4:-1}
tp_match=${TP_MATCH:-$build/bin/tp-match}
tp_chain=${TP_CHAIN:-$build/bin/tp-chain}
bench=${BENCH_TRIFOCAL:-$build/bin/bench_trifocal}
here=$(cd "$(dirname "$0")" && pwd)
data=${TPKIT_SHARED_DIR:-$here/../../shared}/data/pleiades-marseille
mkdir -p "$work"
for p in "1 2" "1 3" "2 3"; do
  set -- $p
  out="$work/m$1$2.matches"
  [ -s "$out" ] || "$tp_match" "$data/img_0$1.tif" "$data/img_0$2.tif" -o "$out"
done
[ -s "$work/real.tracks" ] ||
  "$tp_chain" "$work/m12.matches" "$work/m13.matches" "$work/m23.matches" --min-views 3 -o "$work/real.tracks"
"$bench" --real "$work/real.tracks" --trials "$trials" --seed "$seed"
