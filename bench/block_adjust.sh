#!/usr/bin/env bash
# bench/block_adjust.sh: a block of many images from images to adjusted models, against tp-synth's truth
# (issue 24). A tp-synth block of 12 views (4 dates x tri-stereo, footprints overlapping in part),
# random biases of up to PX pixels (shift, drift and affine terms) on views 2..12, view 1 unbiased and
# fixed; tp-plan's pairs (every pair whose RPC footprints overlap), tp-match on each, tp-chain (tracks of
# any length), rpc-adjust --model affine and tp-ground, run by make; then the adjusted models put the
# truth ground points on the truth pixels (RMS per view: bench_rpc_truth) and the ground heights are
# compared with the truth terrain. The same adjustment on the noise-free truth tracks, and the biased
# models before any adjustment, for scale.
# Tie points fix the block's relative geometry, not its height datum: with one image fixed, a motion of
# every ground point along that image's rays, with a shift of every other image, fits them as well
# (rpc-adjust(1)); the truth DEM is the height prior here (--dem), as a reference DEM would be.
#   bash bench/block_adjust.sh [OUT]          (default OUT: a new folder under /tmp)
#   VIEWS (12), DATES (VIEWS/3), SIZE (1024), SEED (1), PX (10), JOBS (nproc), BIN (build/bin)
set -euo pipefail
if [ "${1:-}" = "--help" ] || [ "${1:-}" = "-h" ]; then sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0; fi
cd "$(dirname "$0")/.."
BIN=$(cd "${BIN:-build/bin}" && pwd)
export PATH="$BIN:$PATH"
OUT=${1:-$(mktemp -d /tmp/tpkit-block.XXXXXX)}
VIEWS=${VIEWS:-12}
DATES=${DATES:-$((VIEWS / 3))}
SIZE=${SIZE:-1024}
SEED=${SEED:-1}
PX=${PX:-10}
JOBS=${JOBS:-$(nproc)}
mkdir -p "$OUT"
cd "$OUT"
t() { local s=$(date +%s.%N); "$@"; echo "  ($(echo "$(date +%s.%N) - $s" | bc) s)"; }
views=() biased=() adjusted=() truthadj=()
for i in $(seq "$VIEWS"); do
  views+=("syn/view$i.tif")
  biased+=("syn/view${i}_rpc.txt")
  adjusted+=("work/adjusted/view${i}_rpc.txt")
  truthadj+=("truth-adjusted/view${i}_rpc.txt")
done

echo "== tp-synth: $VIEWS views, $DATES dates, ${SIZE}^2, biases up to $PX px on views 2..$VIEWS"
[ -f syn/truth.tracks ] || t tp-synth -o syn --views "$VIEWS" --dates "$DATES" --size "$SIZE" --seed "$SEED" --random-bias "$PX"
grep -E '^# (footprint_overlap|tracks_by_views):' syn/truth.tracks

echo "== tp-plan + make -j$JOBS: pairs, tp-match, tp-chain, rpc-adjust --model affine --fixed view1, tp-ground"
[ -d work ] || tp-plan -o work "${views[@]}" --fixed syn/view1.tif --adjust-model affine --adjust-options "--dem syn/truth.dem.tif" \
  --ground-options "--flag 1"
t make -s -C work -f plan.mk -j"$JOBS" >/dev/null
echo "pairs matched: $(ls work/pairs/*.matches | wc -l), matches: $(cat work/pairs/*.matches | grep -vc '^#')"
grep -E '^# tracks_by_views:' work/tracks.tracks
grep -E '^# (rms_before_px|rms_after_px|observations|flagged_tracks):' work/adjusted/rpc.residuals || true

echo "== the biased models as delivered, against the truth"
bench_rpc_truth syn/truth.tracks "${biased[@]}" | tail -n 1
echo "== adjusted from tp-match's tie points"
bench_rpc_truth syn/truth.tracks syn/view1_rpc.txt "${adjusted[@]:1}" --ground work/adjusted/ground.points syn/truth.dem.tif
echo "== tp-ground through the adjusted models (the plan's last stage; --flag 1 px as rpc-adjust's)"
bench_rpc_truth syn/truth.tracks syn/view1_rpc.txt "${adjusted[@]:1}" --ground work/ground.points syn/truth.dem.tif | tail -n 1

# rpc-adjust's weak priors pull every bias term towards 0 (a linear term with sigma 0.01 px per px): on
# noise-free tracks that pull is what remains; --prior-linear 1 shows the geometry without it
for prior in "" "--prior-linear 1"; do
  echo "== adjusted from the noise-free truth tracks ${prior:-(default priors)}"
  rpc-adjust "${views[@]}" --tracks syn/truth.tracks --fixed syn/view1.tif --model affine --dem syn/truth.dem.tif $prior \
    -o truth-adjusted 2>/dev/null
  bench_rpc_truth syn/truth.tracks syn/view1_rpc.txt "${truthadj[@]:1}" --ground truth-adjusted/ground.points syn/truth.dem.tif | tail -n 2
done
