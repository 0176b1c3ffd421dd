#!/usr/bin/env bash
# Images from many dates (issue 51): the twelve WorldView-3 Jacksonville crops of ten dates
# (../shared/data/wv3-jacksonville), every pair against COLMAP 3.8, then the twelve-image block end to end
# against the airborne lidar DSM.
#
#   bench/real_multidate.sh [BUILD_DIR] [WORK_DIR]        (THREADS=2; PAIRS=0 or BLOCK=0 skips a part)
#
# Pairs: tp-match on each of the 66 pairs of the RGB crops (luminance, defaults, --threads 2), every verified
# match written (refined and kept unrefined); COLMAP: feature_extractor (CPU SIFT) + exhaustive_matcher on the
# same RGB files (2 threads), its verified matches read back by tp-convert --from colmap. Both scored by
# bench_epipolar_distance: the distance of x2 y2 from the RPC epipolar curve of x1 y1 (delivered models,
# heights -40..80 m above the ellipsoid), an affine bias of each image's model removed (Huber fit over the
# pair's records). Per pair: tpkit's verified matches, refined share, refined RMS and median distance;
# COLMAP's matches and RMS / median over all of them; and whether the issue's bars hold (refined share
# >= 90%, tpkit's count >= COLMAP's, tpkit's refined RMS <= half COLMAP's). Times: tp-match's sum over the
# pairs, COLMAP's extraction + matching.
# Block: tp-plan + make (pairs, tp-match, tp-chain --unrefined, tp-refine, rpc-adjust with the lidar as a
# height prior at default settings, JAX_068_004 fixed, tp-ground), then tp-ground --compare against the
# lidar with the adjusted models: tracks by length, rpc-adjust's RMS before/after and flagged share, dz =
# h - lidar by slope class (count, median, NMAD); and the same for the pairwise product (the plan's pairs
# chained as tp-plan --no-refine chains them, adjusted alike). tp-refine holds its views to the models
# within about 0.05 px, so rpc-adjust's RMS over refined tracks is small by construction: the lidar is the check. The lidar is first-return and not of the images' dates: slopes under 5 degrees are
# where it is a fair truth.
# COLMAP is a benchmark peer only (never a build or CI dependency): installed here from Debian if missing.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${1:-$here/build}" && pwd)
data=$(cd "$here/../shared/data/wv3-jacksonville" && pwd)
work=${2:-$(mktemp -d /tmp/tpkit-multidate.XXXXXX)}
threads=${THREADS:-2}
bin=$build/bin
for t in tp-match tp-chain tp-plan tp-refine tp-ground tp-convert rpc-adjust bench_epipolar_distance; do
  [ -x "$bin/$t" ] || { echo "missing $bin/$t: build with -DTPKIT_BENCH=ON first" >&2; exit 1; }
done
mkdir -p "$work"
cd "$work"
images=()
for f in "$data"/JAX_068_*_RGB.tif; do images+=("$f"); done
n=${#images[@]}
stem() { basename "$1" _RGB.tif | sed 's/^JAX_068_//'; }
seconds() { awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, a, ":"); s = 0; for (i = 1; i <= n; ++i) s = s * 60 + a[i]; print s}' "$1"; }

if [ "${PAIRS:-1}" != 0 ]; then
  if ! command -v colmap >/dev/null; then
    echo "installing colmap (Debian package, benchmark peer only)" >&2
    if [ "$(id -u)" = 0 ]; then apt-get install -y -qq colmap >/dev/null; else sudo apt-get install -y -qq colmap >/dev/null; fi
  fi
  export QT_QPA_PLATFORM=offscreen
  rm -rf tp colmap colmap.db && mkdir -p tp colmap/images
  for f in "${images[@]}"; do ln -s "$f" colmap/images/; done
  tp_time=0
  for ((i = 0; i < n; ++i)); do
    for ((j = i + 1; j < n; ++j)); do
      a=$(stem "${images[i]}") b=$(stem "${images[j]}")
      /usr/bin/time -v "$bin/tp-match" "${images[i]}" "${images[j]}" --threads "$threads" --cache tp/keypoints -q \
        -o "tp/$a-$b.matches" 2> tp/time.txt >/dev/null || { cat tp/time.txt >&2; exit 1; }
      tp_time=$(awk -v a="$tp_time" -v b="$(seconds tp/time.txt)" 'BEGIN {print a + b}')
    done
  done
  /usr/bin/time -v colmap feature_extractor --database_path colmap.db --image_path colmap/images \
    --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads "$threads" > colmap/extract.log 2> colmap/extract.time
  /usr/bin/time -v colmap exhaustive_matcher --database_path colmap.db \
    --SiftMatching.use_gpu 0 --SiftMatching.num_threads "$threads" > colmap/match.log 2> colmap/match.time
  colmap_time=$(awk -v a="$(seconds colmap/extract.time)" -v b="$(seconds colmap/match.time)" 'BEGIN {print a + b}')
  # COLMAP's image names are the files' names; tp-convert needs the images in the same order
  "$bin/tp-convert" --from colmap colmap.db --images "${images[@]}" -o colmap/matches -q
  echo "== pairs: tp-match $tp_time s for $((n * (n - 1) / 2)) pairs; COLMAP $({ colmap -h 2>&1 || true; } | grep -om1 'COLMAP [0-9.]*' || echo colmap) $colmap_time s (extraction + exhaustive matching), $threads threads"
  printf '%-8s %9s %8s %9s %9s | %8s %9s %9s | %s\n' pair verified refined rms_px med_px colmap rms_px med_px bars
  pass=0 total=0 sum_n=0 sum_ref=0 sum_c=0 min_share=100
  for ((i = 0; i < n; ++i)); do
    for ((j = i + 1; j < n; ++j)); do
      a=$(stem "${images[i]}") b=$(stem "${images[j]}")
      tpf=tp/$a-$b.matches
      read -r _ t_n t_ref _ _ _ _ t_rms t_med < <("$bin/bench_epipolar_distance" "${images[i]}" "${images[j]}" "$tpf" --heights -40,80 | tail -1)
      # COLMAP orders a pair by its image ids: the file may name the two images either way
      si=$(basename "${images[i]}" .tif) sj=$(basename "${images[j]}" .tif)
      if [ -f "colmap/matches/${si}__${sj}.matches" ]; then
        read -r _ c_n _ _ _ c_rms c_med _ _ < <("$bin/bench_epipolar_distance" "${images[i]}" "${images[j]}" "colmap/matches/${si}__${sj}.matches" --heights -40,80 | tail -1)
      elif [ -f "colmap/matches/${sj}__${si}.matches" ]; then
        read -r _ c_n _ _ _ c_rms c_med _ _ < <("$bin/bench_epipolar_distance" "${images[j]}" "${images[i]}" "colmap/matches/${sj}__${si}.matches" --heights -40,80 | tail -1)
      else
        c_n=0 c_rms=nan c_med=nan
      fi
      bars=$(awk -v tn="$t_n" -v tr="$t_ref" -v trms="$t_rms" -v cn="$c_n" -v crms="$c_rms" 'BEGIN {
        s = (tn > 0 && tr / tn >= 0.9) ? "refined>=90%" : "REFINED<90%";
        s = s " " ((tn >= cn) ? "count>=colmap" : "COUNT<COLMAP");
        s = s " " ((crms == "nan" || trms <= crms / 2) ? "rms<=colmap/2" : "RMS>COLMAP/2");
        print s }')
      case $bars in *[A-Z][A-Z]*) ;; *) pass=$((pass + 1)) ;; esac
      total=$((total + 1)) sum_n=$((sum_n + t_n)) sum_ref=$((sum_ref + t_ref)) sum_c=$((sum_c + c_n))
      min_share=$(awk -v m="$min_share" -v a="$t_ref" -v b="$t_n" 'BEGIN {s = b ? 100 * a / b : 0; print (s < m) ? s : m}')
      printf '%-8s %9d %7.1f%% %9.3f %9.3f | %8d %9.3f %9.3f | %s\n' "$a-$b" "$t_n" \
        "$(awk -v a="$t_ref" -v b="$t_n" 'BEGIN {print b ? 100 * a / b : 0}')" "$t_rms" "$t_med" "$c_n" "$c_rms" "$c_med" "$bars"
    done
  done
  echo "pairs meeting every bar: $pass of $total; tpkit $sum_n verified matches, $sum_ref refined ($(awk -v a="$sum_ref" -v b="$sum_n" 'BEGIN {printf "%.1f", 100 * a / b}')%, least share of a pair $(printf '%.1f' "$min_share")%); COLMAP $sum_c"
fi

if [ "${BLOCK:-1}" != 0 ]; then
  rm -rf block block-pairwise && lidar=$data/lidar_dsm_utm17n.tif
  fixed=$data/JAX_068_004_RGB.tif
  adjust_options=(--iterations 400 --dem "$lidar")
  "$bin/tp-plan" -o block "${images[@]}" --fixed "$fixed" --adjust-options "${adjust_options[*]}" -q
  start=$(date +%s.%N)
  PATH=$bin:$PATH make -s -C block -f plan.mk -j"$threads" > block/make.log 2>&1 || { tail -20 block/make.log >&2; exit 1; }
  block_s=$(awk -v s="$start" -v e="$(date +%s.%N)" 'BEGIN {printf "%.0f", e - s}')
  # the pairwise product beside it: the same pairs chained as tp-plan --no-refine chains them (refined
  # matches only), adjusted the same way
  mkdir -p block-pairwise
  "$bin/tp-chain" -q --rpc-check 1 --threads "$threads" --images "${images[@]}" -o block-pairwise/tracks.tracks block/pairs/*.matches
  "$bin/rpc-adjust" "${images[@]}" --tracks block-pairwise/tracks.tracks --model affine --fixed "$fixed" --threads "$threads" \
    "${adjust_options[@]}" -o block-pairwise/adjusted 2> block-pairwise/adjust.log
  # one block's figures: TRACKS ADJUSTED_DIR LABEL
  score_block() {
    local rpc=() f tracks flagged
    for f in "${images[@]}"; do rpc+=(--rpc "$f=$2/$(basename "$f" .tif)_rpc.txt"); done
    "$bin/tp-ground" "${images[@]}" --tracks "$1" "${rpc[@]}" --compare "$lidar" --dz "$2/../block.dz" \
      -o "$2/../block-ground.points" 2> "$2/../compare.log"
    echo "== $3"
    grep -m1 '^# tracks_by_views' "$1"
    awk '/^# (rms_before_px|rms_after_px|rms_after_unflagged_px|flagged_tracks|tracks|dem_prior[a-z_]*):/' "$2/rpc.residuals"
    tracks=$(grep -vc '^#' "$1")
    flagged=$(awk '/^# flagged_tracks:/ {print $3}' "$2/rpc.residuals")
    echo "flagged share: $(awk -v f="${flagged:-0}" -v t="$tracks" 'BEGIN {printf "%.2f%%", 100 * f / t}') of $tracks tracks"
    echo "dz = h - lidar (m), adjusted models, unflagged tracks:"
    grep -vE '^# (written-by|tpkit)' "$2/../block.dz"
  }
  score_block block/refined.tracks block/adjusted \
    "block: $n images, pairs + tp-match + tp-chain --unrefined + tp-refine + rpc-adjust (lidar prior, defaults) + tp-ground in $block_s s"
  grep -iE 'contradict|prior|warning' block/make.log | head -5 || true
  grep -m1 '^# highpass' block/refined.tracks || true
  score_block block-pairwise/tracks.tracks block-pairwise/adjusted "the pairwise product (tp-plan --no-refine's chain: refined matches only), adjusted the same way"
fi
echo "work folder: $work"
