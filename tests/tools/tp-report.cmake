# tp-report: one page from a run's folder (tp-synth scene, trifocal fit with a held-out check, an RPC
# adjustment), opened in headless Chromium; missing input refused without a page.
set(_run "tp-synth -o run/syn --size 256 --points 600 --seed 3 --rpc-bias 2:3,-2 >/dev/null 2>&1 && (grep '^#' run/syn/truth.tracks; grep -v '^#' run/syn/truth.tracks | head -400) > run/fit.tracks && (grep '^#' run/syn/truth.tracks; grep -v '^#' run/syn/truth.tracks | tail -200) > run/check.tracks && trifocal-fit -m affine-dlt run/fit.tracks -o run/t.trifocal && reproj-eval run/t.trifocal run/fit.tracks --check run/check.tracks -o run/fit.eval && rpc-adjust run/syn/view1.tif run/syn/view2.tif run/syn/view3.tif --tracks run/syn/truth.tracks --fixed run/syn/view1.tif --model shift -o run/adjusted 2>/dev/null")
tpkit_tool_test(tp-report.run-in-browser
  COMMAND "${_run} && tp-report run -o page.html --title 'synthetic run' && grep -c '<svg ' page.html && test \"$(grep -o 'rmse_px: [0-9.e-]*' page.html | head -1)\" = \"$(grep '^# rmse_px:' run/fit.eval | cut -c3-)\" && echo summary line shown && grep -c 'class=\"note\"[^>]*>RMSE' page.html && bash $SRC/tests/tools/report_check.sh page.html 1400 2400"
  STDOUT_MATCH "^[4-9]\nsummary line shown\n[1-9][0-9]\npage ok: 1400x2400[^\n]*\nsummary box shown: [0-9]+ pixels\n$")
tpkit_tool_test(tp-report.blank-page-refused-by-the-check
  COMMAND "printf '<!DOCTYPE html><html><body><p>nothing</p></body></html>' > blank.html && bash $SRC/tests/tools/report_check.sh blank.html 800 600"
  EXPECT_FAIL STDERR_MATCH "no colour|nearly blank")
tpkit_tool_test(tp-report.missing-input
  COMMAND "tp-report nowhere -o page.html"
  EXPECT_FAIL STDERR_MATCH "tp-report: nowhere: no such file or folder" NO_FILE page.html)
tpkit_tool_test(tp-report.unreadable-file-listed
  COMMAND "printf '# tpkit tracks 1\\n# columns: track x1 y1\\n1 2 oops\\n' > bad.tracks && tp-report bad.tracks -o page.html && grep -c 'class=\"error\"' page.html"
  STDOUT_MATCH "^1\n")
# A value a kind writes as nan (a dem-dz file's empty slope class, an accuracy file's point not intersected)
# is shown, not taken for an unreadable file.
tpkit_tool_test(tp-report.nan-values-shown
  COMMAND "printf '# tpkit dem-dz 1\\n# columns: stage class slope_min slope_max count median\\n0 0 0 90 10 0.5\\n0 5 40 90 0 nan\\n' > g.dz && tp-report g.dz -o page.html && grep -c 'class=\"error\"' page.html; grep -c '>nan<\\|nan' page.html"
  STDOUT_MATCH "^0\n[1-9]")

# The summary box (issue 53): a run of two matched pairs, tie tracks and an adjustment with check points; its
# figures computed again from the files by report_summary_check.sh (counts from the records, statistics
# from the files' summary lines), and the box above the header dumps.
set(_glance "tp-synth -o syn --size 256 --points 300 --seed 5 --rpc-bias 1:4,-3 --rpc-bias 2:-5,2 >/dev/null 2>&1 && awk -v TIES=syn/ties.tracks -f $SRC/bench/gcp_from_truth.awk syn/truth.tracks > syn/points.gcp && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/ties.tracks --gcp syn/points.gcp -o adj 2>/dev/null && tp-match syn/view1.tif syn/view2.tif -q -o m12.matches && tp-match syn/view2.tif syn/view3.tif -q -o m23.matches")
tpkit_tool_test(tp-report.summary-box
  COMMAND "${_glance} && tp-report m12.matches m23.matches syn/ties.tracks adj --no-coverage -o page.html && bash $SRC/tests/tools/report_summary_check.sh page.html --matches m12.matches m23.matches --tracks syn/ties.tracks --residuals adj/rpc.residuals --accuracy adj/accuracy"
  STDOUT_MATCH "^ok s-matches\nok s-tracks-1\nok s-adjustment-1\nok s-flagged-1\nok s-check-1\n$")
# The check above fails on a box whose figure differs from the files' (a match record left out).
tpkit_tool_test(tp-report.summary-check-can-fail
  COMMAND "${_glance} && tp-report m12.matches m23.matches --no-coverage -o page.html && sed -i '$d' m23.matches && bash $SRC/tests/tools/report_summary_check.sh page.html --matches m12.matches m23.matches"
  EXPECT_FAIL STDERR_MATCH "s-matches: the page says '[0-9]+ matches in 2 pairs")

# Orthos in place (issue 53): three Jacksonville crops orthorectified by gdalwarp (the test peer) onto one
# UTM grid over the lidar DSM at 0.3 m (853 x 853 pixels: the whole-grid flicker is reduced twice, so a
# full-resolution flicker of the centre is drawn as well); "after" made on a flat height instead, on the same
# grid. The page holds, for each set, a flicker of one frame per date (twice), a checkerboard, and a
# thumbnail per ortho; the footprints come from the images' RPCs where the run's tracks name the images (003
# and 004), else from the ortho's valid pixels (006); opened
# in headless Chromium, where the summary box shows at the top.
set(_jax "$SHARED/data/wv3-jacksonville")
set(_warp "gdalwarp -q -rpc -t_srs EPSG:32617 -te 436079 3357496 436335 3357752 -tr 0.3 0.3 -r bilinear -dstnodata 0 -co TILED=YES -co COMPRESS=DEFLATE")
set(_orthos "mkdir -p before after && for i in 003 004 006 @SEMI@ do ${_warp} -to RPC_DEM=${_jax}/lidar_dsm_utm17n.tif ${_jax}/JAX_068_\${i}_RGB.tif before/JAX_068_\${i}_RGB.ortho.tif 2>/dev/null && ${_warp} -to RPC_HEIGHT=-20 ${_jax}/JAX_068_\${i}_RGB.tif after/JAX_068_\${i}_RGB.ortho.tif 2>/dev/null || exit 1 @SEMI@ done")
set(_jax_tracks "printf '# tpkit tracks 1\\n# image1: %s 771 813\\n# image2: %s 0 0\\n# columns: track x1 y1 x2 y2\\n1 10 10 12 12\\n' ${_jax}/JAX_068_003_RGB.tif ${_jax}/JAX_068_004_RGB.tif > jax.tracks")
tpkit_tool_test(tp-report.orthos-in-page
  COMMAND "${_orthos} && ${_jax_tracks} && tp-report jax.tracks --no-coverage --orthos-before before --orthos-after after/JAX_068_004_RGB.ortho.tif --orthos-after after/JAX_068_003_RGB.ortho.tif --orthos-after after/JAX_068_006_RGB.ortho.tif -o page.html 2> err && cat err && grep -o '<svg id=\"flicker[a-z-]*\" class=\"flicker\" data-frames=\"[0-9]*\"' page.html && echo frames $(grep -c '<g class=\"frame\"' page.html) && grep -o 'id=\"checkerboard-[a-z]*\"' page.html && echo thumbnails $(grep -o 'id=\"thumbs-[a-z]*\"\\|<figure class=\"ortho\"><img' page.html | tr '\\n' ' ') && echo footprints $(grep -o 'JAX_068_00[346]_RGB ([A-Za-z ]*)' page.html | sort -u | tr '\\n' ' ') && bash $SRC/tests/tools/report_check.sh page.html 1400 2400"
  STDOUT_MATCH "^tp-report: page.html: 1 files, 3 orthos before and 3 after, [0-9]+ KiB\n<svg id=\"flicker-before\" class=\"flicker\" data-frames=\"3\"\n<svg id=\"flicker-after\" class=\"flicker\" data-frames=\"3\"\n<svg id=\"flicker-zoom-before\" class=\"flicker\" data-frames=\"3\"\n<svg id=\"flicker-zoom-after\" class=\"flicker\" data-frames=\"3\"\nframes 12\nid=\"checkerboard-before\"\nid=\"checkerboard-after\"\nthumbnails id=\"thumbs-before\" <figure class=\"ortho\"><img <figure class=\"ortho\"><img <figure class=\"ortho\"><img id=\"thumbs-after\" <figure class=\"ortho\"><img <figure class=\"ortho\"><img <figure class=\"ortho\"><img\nfootprints JAX_068_003_RGB \\(RPC\\) JAX_068_004_RGB \\(RPC\\) JAX_068_006_RGB \\(valid pixels\\)\npage ok: 1400x2400.*\nsummary box shown: [0-9]+ pixels\n"
  TIMEOUT 120)
# Orthos not on one grid: the one off the first's grid is refused, named, and no page is written.
tpkit_tool_test(tp-report.orthos-off-grid-refused
  COMMAND "mkdir -p o && ${_warp} -to RPC_DEM=${_jax}/lidar_dsm_utm17n.tif ${_jax}/JAX_068_003_RGB.tif o/a.ortho.tif 2>/dev/null && gdal_translate -q -a_ullr 436080 3357752 436335.9 3357496.1 o/a.ortho.tif o/b.ortho.tif && ${_jax_tracks} && tp-report jax.tracks --orthos-before o -o page.html"
  EXPECT_FAIL STDERR_MATCH "tp-report: o/b.ortho.tif: not on the grid of o/a.ortho.tif: its (origin|pixel steps) differ" NO_FILE page.html)
tpkit_tool_test(tp-report.orthos-folder-without-any
  COMMAND "mkdir -p empty && printf '# tpkit tracks 1\\n# columns: track x1 y1 x2 y2\\n1 1 1 2 2\\n' > t.tracks && tp-report t.tracks --orthos-after empty -o page.html"
  EXPECT_FAIL STDERR_MATCH "tp-report: --orthos-after empty: no \\*.ortho.tif file in the folder" NO_FILE page.html)
tpkit_tool_test(tp-report.ortho-not-georeferenced
  COMMAND "printf '# tpkit tracks 1\\n# columns: track x1 y1 x2 y2\\n1 1 1 2 2\\n' > t.tracks && cp ${_jax}/JAX_068_003_RGB.tif plain.tif && tp-report t.tracks --orthos-before plain.tif -o page.html"
  EXPECT_FAIL STDERR_MATCH "tp-report: plain.tif: (no GeoTIFF keys|no georeferencing|no CRS)" NO_FILE page.html)
