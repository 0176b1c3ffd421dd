#!/usr/bin/env bash
# bench/ortho_alignment.sh: how well the orthos of a block overlay before and after rpc-adjust (issue 53),
# measured by tp-ortho --compare. The Jacksonville crops (../shared/data/wv3-jacksonville; by default all
# twelve, FOUR=1: the four dates of docs/blocks.md, 003 004 006 007) are matched and adjusted by a tp-plan run
# (JAX_068_004 fixed, --iterations 400 as docs/blocks.md, the lidar DSM as the height prior: the surface the
# orthos are made on), then orthorectified onto the lidar DSM on one grid (the union of their footprints,
# 0.31 m), through the delivered models and through the adjusted ones (--like: the same grid), twice: as
# gdalwarp does (hidden ground keeps what hides it; every pair's shift per 128-pixel tile) and as true orthos
# (--occluded nodata: hidden ground and the DSM's walls nodata; per 64-pixel tile, the holes leave few
# 128-pixel tiles 95% valid).
# Prints, before and after: the median over the pairs of the pair's median shift (px and m), the largest,
# and the median spread (NMAD) within a pair.
#   bash bench/ortho_alignment.sh [OUT]     (default OUT: a new folder under /tmp; BIN (build/bin), FOUR)
set -euo pipefail
if [ "${1:-}" = "--help" ] || [ "${1:-}" = "-h" ]; then sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 0; fi
cd "$(dirname "$0")/.."
BIN=$(cd "${BIN:-build/bin}" && pwd)
export PATH="$BIN:$PATH"
J=$(cd ../shared/data/wv3-jacksonville && pwd)
OUT=${1:-$(mktemp -d /tmp/tpkit-ortho-alignment.XXXXXX)}
mkdir -p "$OUT"
cd "$OUT"
if [ "${FOUR:-0}" = 1 ]; then ids=(003 004 006 007); else ids=(001 003 004 006 007 009 011 012 014 015 018 020); fi
imgs=()
for i in "${ids[@]}"; do imgs+=("$J/JAX_068_${i}_RGB.tif"); done
echo "== tp-plan + make: ${#ids[@]} crops, JAX_068_004 fixed, the lidar DSM as the height prior"
[ -f jax/adjusted/rpc.bias ] || {
  tp-plan -o jax "${imgs[@]}" --fixed "$J/JAX_068_004_RGB.tif" --adjust-options "--iterations 400 --dem $J/lidar_dsm_utm17n.tif" 2>/dev/null
  make -s -C jax -f plan.mk -j2 >/dev/null 2>&1
}
grep -E '^# (rms_before_px|rms_after_unflagged_px)' jax/adjusted/rpc.residuals || true
rpc=()
for i in "${ids[@]}"; do rpc+=(--rpc "$J/JAX_068_${i}_RGB.tif=jax/adjusted/JAX_068_${i}_RGB_rpc.txt"); done
echo "== tp-ortho onto the lidar DSM: delivered models, then adjusted models on the same grid; as gdalwarp, then true orthos"
tp-ortho "${imgs[@]}" --dem "$J/lidar_dsm_utm17n.tif" --threads 2 -o before 2>&1 | grep -E 'grid' || true
tp-ortho -q "${imgs[@]}" --dem "$J/lidar_dsm_utm17n.tif" --threads 2 --like "before/JAX_068_${ids[0]}_RGB.ortho.tif" "${rpc[@]}" -o after 2>/dev/null
tp-ortho -q "${imgs[@]}" --dem "$J/lidar_dsm_utm17n.tif" --threads 2 --like "before/JAX_068_${ids[0]}_RGB.ortho.tif" --occluded nodata -o before-true 2>/dev/null
tp-ortho "${imgs[@]}" --dem "$J/lidar_dsm_utm17n.tif" --threads 2 --like "before/JAX_068_${ids[0]}_RGB.ortho.tif" "${rpc[@]}" --occluded nodata -o after-true 2>&1 |
  grep -oE '[^ ]*_RGB.tif -> .*hidden' | sed -E 's|.*/(JAX_068_[0-9]+)_RGB.tif -> .*valid, |true ortho \1: |' || true
tp-ortho -q --compare before/*.ortho.tif --threads 2 -o before.alignment
tp-ortho -q --compare after/*.ortho.tif --threads 2 -o after.alignment
tp-ortho -q --compare before-true/*.ortho.tif --threads 2 --tile 64 -o before-true.alignment
tp-ortho -q --compare after-true/*.ortho.tif --threads 2 --tile 64 -o after-true.alignment
# median of a column of numbers on stdin
median() { sort -g | awk '{ v[NR] = $1 } END { if (NR == 0) print "nan"; else print (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2) }'; }
for s in before after before-true after-true; do
  rows=$(grep -v '^#' $s.alignment | awk '$3 > 0')
  n=$(echo "$rows" | grep -c . || true)
  [ "$n" -gt 0 ] || { echo "$s: no pair measured"; continue; }
  printf '%-11s %d of %d pairs measured, %d tiles: median shift %.2f px (%.2f m), largest %.2f px (%.2f m), median NMAD %.2f px\n' \
    "$s" "$n" "$(grep -vc '^#' $s.alignment)" "$(echo "$rows" | awk '{ t += $3 } END { print t }')" \
    "$(echo "$rows" | awk '{ print $9 }' | median)" "$(echo "$rows" | awk '{ print $12 }' | median)" \
    "$(echo "$rows" | awk '{ print $9 }' | sort -g | tail -n 1)" "$(echo "$rows" | awk '{ print $12 }' | sort -g | tail -n 1)" \
    "$(echo "$rows" | awk '{ print ($7 > $8 ? $7 : $8) }' | median)"
done
