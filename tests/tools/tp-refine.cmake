# tp-refine on tp-synth's truth tracks: the template keeps its position, so the refined views must stay on
# the truth (the views of a truth track are the projections of one ground point); the output has the
# sigma and template columns. Bad input: a tracks image not among the images given, nothing written.
set(_scene "tp-synth --out s --size 256 --points 60 --relief 20 > /dev/null")
tpkit_tool_test(tp-refine.synth-truth
  COMMAND "${_scene} && tp-refine s/view1.tif s/view2.tif s/view3.tif --tracks s/truth.tracks -o r.tracks && awk 'FNR == 1 { f++ } /^#/ { next } f == 1 { for (i = 2; i <= 7; i++) t[$1, i] = $i; next } { for (i = 2; i <= 7; i++) if ($i != \"nan\") { d = $i - t[$1, i]; if (d < 0) d = -d; if (d > m) m = d } n++ } END { printf \"refined %d max deviation %.3f\\n\", n, m; exit !(n >= 40 && m < 0.1) }' s/truth.tracks r.tracks"
  STDOUT_MATCH "refined [0-9]+ max deviation 0\\.0"
  STDERR_MATCH "tp-refine: 60 tracks, 180 views: [0-9]+ tracks written"
  CHECK_FILE r.tracks FILE_MATCH "# columns: track x1 y1 x2 y2 x3 y3 .*sigma1 sigma2 sigma3 template\n")
tpkit_tool_test(tp-refine.image-not-given
  COMMAND "${_scene} && tp-refine s/view1.tif s/view2.tif --tracks s/truth.tracks -o r.tracks"
  EXPECT_FAIL STDERR_MATCH "tp-refine: s/truth.tracks: image3 .* is not one of the images given" NO_FILE r.tracks)
tpkit_tool_test(tp-refine.no-tracks
  COMMAND "${_scene} && tp-refine s/view1.tif s/view2.tif -o r.tracks"
  EXPECT_FAIL STDERR_MATCH "tp-refine: --tracks: a tracks file is needed" NO_FILE r.tracks)
tpkit_tool_test(tp-refine.bad-model-sigma
  COMMAND "${_scene} && tp-refine s/view1.tif s/view2.tif s/view3.tif --tracks s/truth.tracks --model-sigma loose -o r.tracks"
  EXPECT_FAIL STDERR_MATCH "tp-refine: --model-sigma: 'auto' or a number of pixels >= 0, got 'loose'" NO_FILE r.tracks)
# The window's size chosen on a sample of the tracks, against the truth (bench_match_accuracy --multi:
# the triplets' views 2 and 3 after the refinement). Gentle relief (15 m over the 256 m scene): taper
# 5 px is chosen (ratio 1.03) and brings the median from 0.0152 px (taper 3 alone) to 0.0132; steep
# relief (150 m): taper 3 px is kept (ratio 2.6), where taper 5 would double the error (0.032 -> 0.067).
if(TPKIT_BENCH)
tpkit_tool_test(tp-refine.size-accuracy
  COMMAND "tp-synth --out g --size 512 --seed 3 --relief 15 > /dev/null && tp-synth --out r --size 512 --seed 3 > /dev/null && for s in g r; do for t in auto 3 5; do bench_match_accuracy --synth $s --threads 2 --multi --multi-taper $t > $s$t.txt || exit 1 @SEMI@ done @SEMI@ grep -h 'LSM size' $s'auto.txt' | cut -c1-50 @SEMI@ done && awk '/after, views 2\\+3/ {for (i = 1; i <= NF; ++i) if ($i == \"median\") m[FILENAME] = $(i + 1)} END {exit !(m[\"gauto.txt\"] < 0.95 * m[\"g3.txt\"] && m[\"rauto.txt\"] == m[\"r3.txt\"] && m[\"r5.txt\"] > 1.5 * m[\"rauto.txt\"])}' gauto.txt g3.txt rauto.txt r3.txt r5.txt"
  STDOUT_MATCH "multi-image LSM size: taper 5 px, window 29 px[^\n]*\nmulti-image LSM size: taper 3 px, window 21 px" TIMEOUT 300)
endif()
