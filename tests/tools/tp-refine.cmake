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
