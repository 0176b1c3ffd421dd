#!/usr/bin/env bash
# bench/multi_image_jax.sh: multi-image least-squares matching (tp-refine) on the Jacksonville block, scored
# against the lidar DSM (issue 52). All twelve WorldView-3 crops through tp-plan's pipeline without its
# refine stage (--no-refine: tp-match on the 66 pairs, tp-chain), then for the pairwise tracks and for
# tp-refine's refined tracks (each VARIANT: its options; tp-refine's high-pass chosen on the tracks) rpc-adjust
# --model affine (004 fixed, 400 iterations, the lidar as height prior, as plan.mk runs it) and tp-ground
# --compare the lidar DSM: tracks, points and NMAD of dz on DEM slopes under 5 degrees and on all slopes.
# (tp-plan's own refine stage also chains the unrefined matches: bench/real_multidate.sh's block.)
#   bash bench/multi_image_jax.sh [OUT]       (default OUT: a new folder under /tmp)
#   BIN (build/bin), JOBS (2), VARIANTS ("--no-extend|"; '|' between variants, an empty one: the defaults)
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$(mktemp -d /tmp/tpkit-mpgc-jax.XXXXXX)}
BIN=${BIN:-$src/build/bin}; JOBS=${JOBS:-2}
VARIANTS=${VARIANTS-"--no-extend|"}
export PATH=$(cd "$BIN" && pwd):$PATH
J=$src/../shared/data/wv3-jacksonville
imgs=("$J"/JAX_068_*_RGB.tif)
mkdir -p "$out" && cd "$out"
[ -s jax/tracks.tracks ] || {
  tp-plan -o jax "${imgs[@]}" --fixed "$J/JAX_068_004_RGB.tif" --no-refine --adjust-options "--iterations 400 --dem $J/lidar_dsm_utm17n.tif" > /dev/null 2>&1
  make -s -C jax -f plan.mk -j"$JOBS" > jax.log 2>&1
}
# rpc-adjust and tp-ground --compare on tracks file $1, in folder $2; prints one line
score() {
  mkdir -p "$2"
  rpc-adjust "${imgs[@]}" --tracks "$1" --model affine --fixed "$J/JAX_068_004_RGB.tif" --iterations 400 --dem "$J/lidar_dsm_utm17n.tif" \
    -o "$2/adjusted" 2> "$2/adjust.log"
  local rpc=() i
  for i in "${imgs[@]}"; do rpc+=(--rpc "$i=$2/adjusted/$(basename "$i" .tif)_rpc.txt"); done
  tp-ground "${imgs[@]}" --tracks "$1" "${rpc[@]}" --compare "$J/lidar_dsm_utm17n.tif" --dz "$2/ground.dz" -o "$2/ground.points" 2> "$2/ground.log"
  awk -v what="$3" -v n="$(grep -vc '^#' "$1")" '!/^#/ && $1 == 0 && $2 == 1 { f = sprintf("%d points, NMAD %.3f m", $5, $7) }
       !/^#/ && $1 == 0 && $2 == 0 { a = sprintf("%d points, NMAD %.3f m", $5, $7) }
       END { printf "%-44s tracks %5d  slope < 5 deg: %s  all: %s\n", what, n, f, a }' "$2/ground.dz"
}
score jax/tracks.tracks pairwise "tp-chain (pairwise)"
IFS='|' read -ra vs <<< "$VARIANTS|"
k=0
for v in "${vs[@]}"; do
  k=$((k + 1))
  # shellcheck disable=SC2086
  tp-refine "${imgs[@]}" --tracks jax/tracks.tracks --threads "$JOBS" $v -o "refined$k.tracks" 2> "refined$k.log"
  score "refined$k.tracks" "refined$k" "tp-refine ${v:-(defaults)}"
done
