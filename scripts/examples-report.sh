#!/usr/bin/env bash
# Collects the tables and figures of Makefile.examples into one Markdown page (stdout).
#   examples-report.sh OUT NAME "IMAGES" "NPOINTS" "METHODS" TERRAIN
# (TERRAIN: the folder of the plain and mountain scenes, which every report shares)
set -euo pipefail
[ $# -eq 6 ] || { echo "usage: $0 OUT NAME IMAGES NPOINTS METHODS TERRAIN" >&2; exit 2; }
out=$1 name=$2 images=$3 npoints=$4 methods=$5 terrain=$6
rel() { realpath -m --relative-to="$out" "$1"; }
count() { grep -vc '^#' "$1" 2>/dev/null || echo 0; }
echo "# tpkit experiments: $name"
echo
echo "Images: $(for i in $images; do printf '`%s` ' "$i"; done)"
echo
echo "Triplet tracks (tp-match on the three pairs, then tp-chain): **$(count "$out/triplet.tracks")**, of which"
echo "$(count "$out/triplet-inliers.tracks") are inliers of a robust affine trifocal fit (trifocal-fit --ransac drops"
echo "mismatches that slid along an epipolar line, which pair verification cannot see);"
echo "pair matches: 1-2 $(count "$out/pair-1-2.matches"), 1-3 $(count "$out/pair-1-3.matches"), 2-3 $(count "$out/pair-2-3.matches")."
echo "Fit points are drawn from the inlier tracks by \`tp-sample\` with a fixed seed; every other track is a"
echo "held-out check point. RMSE is the square root of the mean squared 2-D reprojection residual over all"
echo "points and the three views, after camera recovery from the tensor and DLT triangulation (reproj-eval)."
echo
for t in "$out"/table-1-2.md "$out"/table-3-4.md "$out"/table-5-6.md; do
  [ -f "$t" ] && cat "$t"
done
echo "## Error distributions (Yang, Pan, Huang figures 3-8)"
echo
for n in $npoints local global; do
  for m in ml $(echo "$methods" | tr ' ' '\n' | grep -vx ml | head -n 1); do
    f=$out/fit-$n-$m.svg
    [ -f "$f" ] && echo "- $n points, $m: ![]($(rel "$f"))"
  done
done
for s in plain mountain; do
  f=$terrain/$s/fit-100-ml.svg
  [ -f "$f" ] && echo "- $s terrain, 100 points, ml: ![]($(rel "$f"))"
done
echo
echo "## Point clusters (Navy et al. figures 2, 5, 6)"
echo
for f in "$out"/clusters/*.svg; do
  [ -f "$f" ] && echo "- $(basename "$f" .svg): ![]($(rel "$f"))"
done
echo
