#!/usr/bin/env bash
# The demo pipeline, complete on its own on a fresh Debian 12 machine (as root): installs what is
# missing, builds, generates a synthetic Pléiades-like triplet with exact ground truth, and runs
#   tp-synth -> tp-match (3 pairs) -> tp-chain -> trifocal-fit (robust) -> reproj-eval
# writing every intermediate file into demo-out/ (or the folder given as the first argument).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh tools
bin=$PWD/build/bin
out=${1:-demo-out}
mkdir -p "$out"
cd "$out"
t0=$(date +%s.%N)
step() { printf '\n== %s\n' "$*"; }

step "tp-synth: a 1024 x 1024 triplet with 150 m relief, affine cameras, seed 1 -> scene/"
"$bin"/tp-synth --out scene --size 1024 --relief 150 --seed 1

step "tp-match: the three pairs (SIFT, affine-F RANSAC, least-squares refinement)"
"$bin"/tp-match scene/view1.tif scene/view2.tif --cache keypoints -o pair-1-2.matches
"$bin"/tp-match scene/view1.tif scene/view3.tif --cache keypoints -o pair-1-3.matches
"$bin"/tp-match scene/view2.tif scene/view3.tif --cache keypoints -o pair-2-3.matches

step "tp-chain: tracks seen in all three views"
"$bin"/tp-chain pair-1-2.matches pair-1-3.matches pair-2-3.matches \
  --images scene/view1.tif scene/view2.tif scene/view3.tif -o triplet.tracks

step "trifocal-fit: robust maximum-likelihood affine fit (flags mismatches), then the affine DLT on the inliers"
"$bin"/trifocal-fit -m ml --ransac 1.5 triplet.tracks --inliers triplet-flagged.tracks -o fit-ml.trifocal
awk '/^# columns:/ { for (i = 3; i <= NF; i++) if ($i == "inlier") c = i - 2 } /^#/ { print; next } $c == 1' \
  triplet-flagged.tracks > triplet-inliers.tracks
"$bin"/trifocal-fit -m affine-dlt triplet-inliers.tracks -o fit-affine-dlt.trifocal

step "reproj-eval: reprojection errors (and a plot), and the true tensor on the true points"
"$bin"/reproj-eval fit-ml.trifocal triplet-inliers.tracks --plot fit-ml.svg -o fit-ml.eval
"$bin"/reproj-eval fit-affine-dlt.trifocal triplet-inliers.tracks -o fit-affine-dlt.eval
"$bin"/reproj-eval scene/truth.trifocal scene/truth.tracks -o truth.eval
for f in fit-ml.eval fit-affine-dlt.eval truth.eval; do
  printf '%-20s %s\n' "$f" "$(grep -E '^# (n|rmse_px):' "$f" | tr '\n' ' ')"
done

t1=$(date +%s.%N)
step "done in $(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b - a}') s; results in $PWD:"
ls -1
