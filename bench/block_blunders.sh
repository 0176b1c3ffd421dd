#!/usr/bin/env bash
# bench/block_blunders.sh: the share of a real block's tracks that rpc-adjust flags as blunders, and the
# tracks by length, from the same pairwise matches chained three ways (issue 51): tp-chain with the loop
# closure only (--closure 0.5, every cycle of each track), without any check (--closure 0), and with the
# RPC check as tp-plan runs it (--rpc-check 1). The block: the twelve WorldView-3 crops of Jacksonville
# (../shared/data/wv3-jacksonville, ten dates), tp-plan's pairs matched by tp-match (the plan's make run,
# kept in WORK), one image fixed, rpc-adjust --model affine --iterations 400 (as docs/blocks.md).
#   bash bench/block_blunders.sh [WORK]     (from the top of a built tree, ../shared beside it; about
#                                            6 min on 2 cores, most of it the matching)
# Prints per variant: tracks by length, views dropped, the flagged tracks (count, share, by length),
# the RMS over the unflagged tracks, the solver's iterations.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
bin=$top/build/bin
J=$top/../shared/data/wv3-jacksonville
W=${1:-$(mktemp -d)}
export PATH=$bin:$PATH
imgs=$(ls "$J"/JAX_068_*_RGB.tif)
if [ ! -s "$W/plan/tracks.tracks" ]; then
  tp-plan -q -o "$W/plan" $imgs --no-adjust
  make -s -C "$W/plan" -f plan.mk -j2 >/dev/null
fi
run() {
  local name=$1; shift
  local d=$W/$name
  mkdir -p "$d"
  tp-chain -q --images $imgs -o "$d/tracks.tracks" "$@" -- "$W"/plan/pairs/*.matches
  rpc-adjust $imgs --tracks "$d/tracks.tracks" --model affine --fixed "$J/JAX_068_004_RGB.tif" --iterations 400 \
    -o "$d/adjusted" 2> "$d/adjust.log" || true
  local it
  it=$(grep -o '[0-9]* iterations' "$d/adjust.log" | head -1)
  echo "== $name: $(grep -E '^# tracks_by_views' "$d/tracks.tracks")"
  grep -E '^# (closure|rpc_check):' "$d/tracks.tracks" | sed 's/^/   /'
  awk -v it="$it" '
    /^# rms_after_unflagged_px:/ { rms = $3 }
    !/^#/ { v[$1]++; if ($9 == 1) f[$1] = 1 }
    END {
      for (t in v) { n[v[t]]++; if (f[t]) F[v[t]]++; N++; FF += f[t] }
      s = ""; for (k = 2; k <= 20; k++) if (k in n) s = s " " k ":" (F[k] + 0) "/" n[k]
      printf "   flagged %d of %d tracks (%.2f%%); by length (flagged/tracks):%s\n   rms over the unflagged %.3f px; %s\n", FF, N, 100 * FF / N, s, rms, it
    }' "$d/adjusted/rpc.residuals"
}
run no-check --closure 0
run closure
run rpc-check --rpc-check 1
