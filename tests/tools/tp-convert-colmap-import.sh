#!/bin/bash
# COLMAP reads what tp-convert writes (tests/tools/tp-convert.cmake): the Marseille pairs from tp-match,
# exported with --to colmap, go through COLMAP's own feature_importer + matches_importer (text form)
# and database_merger (our database.db, read by COLMAP's Database class); COLMAP's databases must hold
# the same keypoints, the same match counts and the same positions. Fails when colmap is missing.
set -euo pipefail
command -v colmap >/dev/null || { echo "colmap is not installed (scripts/install-deps.sh --test installs it)" >&2; exit 1; }
export QT_QPA_PLATFORM=offscreen
D=$SHARED/data/pleiades-marseille
tp-match $D/img_01.tif $D/img_02.tif $D/img_03.tif --cache kp -o pairs -q
tp-convert --to colmap pairs/*.matches -o col
# the text form through COLMAP's importers (raw: COLMAP verifies them itself)
colmap feature_importer --database_path imported.db --image_path $D --import_path col/keypoints > import.log 2>&1 ||
  { cat import.log; exit 1; }
colmap matches_importer --database_path imported.db --match_list_path col/matches.txt --match_type raw >> import.log 2>&1 ||
  { cat import.log; exit 1; }
# our database.db, read by COLMAP and written again
colmap database_creator --database_path empty.db > merge.log 2>&1
colmap database_merger --database_path1 col/database.db --database_path2 empty.db --merged_database_path merged.db >> merge.log 2>&1 ||
  { cat merge.log; exit 1; }
tp-convert --from colmap --colmap-matches raw imported.db -o back-imported -q
tp-convert --from colmap --colmap-matches raw merged.db -o back-merged -q
tp-convert --from colmap col/database.db -o back-ours -q
fail=0
for p in 1-2 1-3 2-3; do
  a=img_0${p%-*} b=img_0${p#*-}
  n=$(grep -vc '^#' pairs/pair-$p.matches)
  ours=$(grep '^# keypoints:' back-ours/${a}__${b}.matches)
  for db in imported merged; do
    f=back-$db/${a}__${b}.matches
    got=$(grep -vc '^#' $f)
    kp=$(grep '^# keypoints:' $f)
    echo "pair $p: tpkit $n matches; COLMAP $db: $got matches, $kp (ours: $ours)"
    [ "$got" = "$n" ] || { echo "match count differs" >&2; fail=1; }
    [ "$kp" = "$ours" ] || { echo "keypoint count differs" >&2; fail=1; }
    # every position equal to float32 (|d| <= 1e-4 px at 1000 px), same order
    awk 'NR == FNR { if (!/^#/) { ++n; a[n] = $2 " " $3 " " $5 " " $6 } next }
         !/^#/ { ++m; split(a[m], o, " ")
                 if ((e = o[1] - $2) * e > 1e-8 || (e = o[2] - $3) * e > 1e-8 || (e = o[3] - $5) * e > 1e-8 || (e = o[4] - $6) * e > 1e-8) bad++ }
         END { if (bad) { print bad " positions differ" > "/dev/stderr"; exit 1 } }' pairs/pair-$p.matches $f || fail=1
  done
done
exit $fail
