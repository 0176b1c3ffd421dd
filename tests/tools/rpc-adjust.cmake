# rpc-adjust: injected biases on two synthetic views (the third fixed, the scene's DEM as height prior) are
# recovered: residuals vanish, the adjusted models give the truth heights; bad input is refused.
set(synth_biased "tp-synth -o syn --size 512 --points 400 --rpc-bias 2:6,-8,0.002,-0.001,0.001,0.0015 --rpc-bias 3:-10,4,0.001,0.0005")
set(adjust "rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks --fixed syn/view1.tif")
tpkit_tool_test(rpc-adjust.recovers-affine-biases
  COMMAND "${synth_biased} && ${adjust} --dem syn/truth.dem.tif -o adj && tp-ground syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks --rpc syn/view2.tif=adj/view2_rpc.txt --rpc syn/view3.tif=adj/view3.RPB -o g.points && paste <(grep -v '^#' syn/truth.tracks) <(grep -v '^#' g.points) | awk '{ s += ($13 - $17)^2 @SEMI@ n++ } END { r = sqrt(s / n) @SEMI@ print (r < 0.25 ? \"heights ok\" : \"heights off\"), r }'"
  STDOUT_MATCH "^heights ok "
  CHECK_FILE adj/rpc.residuals
  FILE_MATCH "# rms_before_px: [1-9][0-9.]*\n# rms_after_px: (0\\.00[0-9]*|[0-9.]+e-[0-9]+)\n.*# flagged_tracks: 0\n")
tpkit_tool_test(rpc-adjust.outputs
  COMMAND "${synth_biased} && ${adjust} --model shift --crs utm -o adj && ls adj | tr '\\n' ' '"
  STDOUT_MATCH "ground.csv ground.csvt ground.geojson ground.points ground.prj residuals.svg rpc.bias rpc.residuals view1.RPB view1_rpc.txt view2.RPB view2_rpc.txt view3.RPB view3_rpc.txt"
  CHECK_FILE adj/ground.points
  FILE_MATCH "^# tpkit ground 1\n.*# crs: EPSG:32631 .*# columns: track easting northing h sigma_h views rms_px flagged\n")
tpkit_tool_test(rpc-adjust.image-without-rpc
  COMMAND "${synth_biased} && rpc-adjust syn/view1.tif syn/truth.dem.tif --tracks syn/truth.tracks -o adj"
  EXPECT_FAIL STDERR_MATCH "\nrpc-adjust: syn/truth.dem.tif: no RPC model" NO_FILE adj/rpc.bias)
tpkit_tool_test(rpc-adjust.malformed-model
  COMMAND "${synth_biased} && sed 's/^LAT_OFF: .*/LAT_OFF: north/' syn/view2_rpc.txt > bad_rpc.txt && ${adjust} --rpc syn/view2.tif=bad_rpc.txt -o adj"
  EXPECT_FAIL STDERR_MATCH "\nrpc-adjust: bad_rpc.txt:5: LAT_OFF: 'north' is not a number" NO_FILE adj)
tpkit_tool_test(rpc-adjust.bad-model
  COMMAND "rpc-adjust a.tif --tracks t --model rotation -o adj"
  EXPECT_FAIL STDERR_MATCH "^rpc-adjust: --model: expected shift, drift or affine")
tpkit_tool_test(rpc-adjust.held-out
  COMMAND "${synth_biased} && tp-sample --help >/dev/null && (grep '^#' syn/truth.tracks @SEMI@ grep -v '^#' syn/truth.tracks | awk 'NR % 2 == 1') > fit.tracks && (grep '^#' syn/truth.tracks @SEMI@ grep -v '^#' syn/truth.tracks | awk 'NR % 2 == 0') > check.tracks && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks fit.tracks --check check.tracks --fixed syn/view1.tif -o adj"
  STDERR_MATCH "held-out [0-9.e-]+ px \\(600 observations\\)")
# A result is written only when the solution is sound (issue 23): another image's model leaves most tracks
# above --flag and fails with the figures; a header naming one image twice, a view off its image (1e300
# made the cost infinite and Ceres stop at once, biases 0), sigmas below a millimetre and a DEM off the
# scene are refused; nothing is left in -o. More in the unit test rpc.RpcTrust.
tpkit_tool_test(rpc-adjust.another-images-model
  COMMAND "${synth_biased} && ${adjust} --rpc syn/view2.tif=syn/view3_rpc.txt -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: image2 syn/view2.tif: [0-9]+ of the 400 tracks that view it keep an RMS above 1 px after the fit or lost that view as a blunder \\([0-9]+\\) \\(its rms [0-9.]+ px before, [0-9.]+ px after\\): its model does not fit them" NO_FILE adj)
tpkit_tool_test(rpc-adjust.one-image-twice
  COMMAND "${synth_biased} && sed 's/^# image2: view2.tif/# image2: view1.tif/' syn/truth.tracks > syn/twice.tracks && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/twice.tracks -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: syn/twice.tracks: image1 and image2 are both syn/view1.tif: a track views each image once" NO_FILE adj)
tpkit_tool_test(rpc-adjust.view-off-the-image
  COMMAND "${synth_biased} && awk '!/^#/ && ++n == 3 { $4 = 1e300 } { print }' syn/truth.tracks > syn/off.tracks && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/off.tracks -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: syn/off.tracks:[0-9]+: track [0-9]+: view 2 at \\(1e\\+300, " NO_FILE adj)
tpkit_tool_test(rpc-adjust.sigmas-below-a-millimetre
  COMMAND "${synth_biased} && (${adjust} --height-prior 200+-1e-300 -o adj @SEMI@ echo \"rc \$?\") && ${adjust} --dem syn/truth.dem.tif --dem-sigma 1e-300 -o adj"
  EXPECT_FAIL STDOUT_MATCH "^rc 2\n" STDERR_MATCH "--height-prior: S = 1e-300 m is below 0.001 m.*\n.*--dem-sigma 1e-300: below 0.001 m" NO_FILE adj)
tpkit_tool_test(rpc-adjust.threads-under-address-limit
  COMMAND "${synth_biased} && (ulimit -v 4000000 && ${adjust} --threads 1024 -o b 2> err) && cat err >&2 && ! grep -E 'WARNING|preprocessor' err"
  STDERR_MATCH "rpc-adjust: warning: the system refused a worker thread .*\nrpc-adjust: 400 tracks, 1200 observations, model affine: rms 8.207 px before, 0.000[0-9]+ px after"
  CHECK_FILE b/rpc.bias FILE_MATCH "# tpkit rpc-bias" LABELS rlimit)
# A height prior that contradicts the tie points (the scene's terrain is near 0 m, the prior says 1000+-5:
# the biases it forces are no delivered model's) is refused with the figures of the fit with and without
# it, nothing written; the scene's own DEM agrees.
tpkit_tool_test(rpc-adjust.contradicting-height-prior
  COMMAND "${synth_biased} && ${adjust} --height-prior 1000+-5 -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: --height-prior 1000\\+-5 contradicts the tie points: rms after [0-9.e-]+ px with it, [0-9.e-]+ px without \\(over the [0-9]+ tracks neither flags\\)@SEMI@ flagged tracks [0-9]+ with, 0 without@SEMI@ prior minus free height: median [0-9.]+ m .*the biases it forces are beyond any delivered model's" NO_FILE adj)
tpkit_tool_test(rpc-adjust.agreeing-dem
  COMMAND "${synth_biased} && ${adjust} --dem syn/truth.dem.tif --strict -o adj"
  STDERR_MATCH "--dem syn/truth.dem.tif agrees with the tie points: rms after [0-9.e-]+ px with it")
# Needs the benchmark program bench_dem_reference (not built in the sanitizer build; runs in the Release suite).
if(TPKIT_BENCH)
# A reference DEM in UTM with EGM96 heights (issue 25; bench_dem_reference, 1 m: the scene is 256 m wide): with --dem-datum egm96,
# or without it (the DEM's vertical keys say EGM96), it agrees with the tie points; --dem-datum ellipsoid (49 m too low)
# disagrees with the keys and is refused (issue 50).
tpkit_tool_test(rpc-adjust.dem-utm-egm96
  COMMAND "${synth_biased} && bench_dem_reference syn/truth.dem.tif ref.tif 1 0 egm96 && ${adjust} --dem ref.tif --dem-datum egm96 --strict -o adj && ${adjust} --dem ref.tif --strict -o adj2 && ${adjust} --dem ref.tif --dem-datum ellipsoid -o adj3"
  EXPECT_FAIL STDERR_MATCH "--dem ref.tif agrees with the tie points: rms after [0-9.e-]+ px with it.*--dem ref.tif agrees with the tie points: rms after [0-9.e-]+ px with it.*rpc-adjust: ref.tif: --dem-datum ellipsoid disagrees with the GeoTIFF keys" NO_FILE adj3)
endif()
tpkit_tool_test(rpc-adjust.dem-datum-without-dem
  COMMAND "rpc-adjust a.tif b.tif --tracks t --dem-datum egm96 -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: --dem-datum goes with --dem")
# Tracks of any length (issue 24): the truth tracks with views blanked to nan nan (2 in 5 keep three views,
# the others miss view 1, 2 or 3 in turn), a version-2 tracks file: 2- and 3-view tracks, reported per image,
# and the adjusted models put the truth ground points at the truth heights (tp-ground on the full tracks).
set(blank "sed 's/^# tpkit tracks 1/# tpkit tracks 2/' syn/truth.tracks | awk '/^#/ { print @SEMI@ next } { n++ } n % 5 == 2 { $2 = $3 = \"nan\" } n % 5 == 3 { $4 = $5 = \"nan\" } n % 5 == 4 { $6 = $7 = \"nan\" } { print }'")
tpkit_tool_test(rpc-adjust.tracks-with-missing-views
  COMMAND "${synth_biased} && ${blank} > syn/mixed.tracks && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/mixed.tracks --fixed syn/view1.tif --dem syn/truth.dem.tif -o adj && tp-ground syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks --rpc syn/view2.tif=adj/view2_rpc.txt --rpc syn/view3.tif=adj/view3.RPB -o g.points && paste <(grep -v '^#' syn/truth.tracks) <(grep -v '^#' g.points) | awk '{ s += ($13 - $17)^2 @SEMI@ n++ } END { r = sqrt(s / n) @SEMI@ print (r < 0.25 ? \"heights ok\" : \"heights off\"), r }'"
  STDOUT_MATCH "^heights ok "
  STDERR_MATCH "rpc-adjust: 400 tracks, 960 observations, .*\nrpc-adjust: tracks by length 2:240 3:160@SEMI@ unit weights \\(no sigma given\\)\nrpc-adjust: image1 syn/view1.tif \\(fixed\\): 320 observations, tracks by length 2:160 3:160, median sigma 1 px, rms [0-9.]+ px before, [0-9.e-]+ px after\nrpc-adjust: image2 syn/view2.tif: 320 observations, tracks by length 2:160 3:160, median sigma 1 px, rms [1-9][0-9.]* px before, 0\\.00[0-9]* px after\n"
  CHECK_FILE adj/rpc.residuals
  FILE_MATCH "# tracks_by_length: 2:240 3:160\n.*# rms_after_px: (0\\.00[0-9]*|[0-9.]+e-[0-9]+)\n.*# image3_observations: 320\n# image3_tracks_by_length: 2:160 3:160\n")
# Matches files given directly (each record a 2-view track; image paths from the header), sigma weighted:
# the pairs 1-2 and 2-3 of the truth with a sigma column, adjusted as the 3-view tracks are.
set(to_matches "awk -v a=1 -v b=2 'BEGIN { print \"# tpkit matches 1\\n# image1: view\" a \".tif\\n# image2: view\" b \".tif\\n# columns: id1 x1 y1 id2 x2 y2 sigma\" } /^#/ { next } { print $1, $(2 * a), $(2 * a + 1), $1, $(2 * b), $(2 * b + 1), 0.05 }' syn/truth.tracks")
string(REPLACE "-v a=1 -v b=2" "-v a=2 -v b=3" to_matches_23 "${to_matches}")
tpkit_tool_test(rpc-adjust.matches-files
  COMMAND "${synth_biased} && ${to_matches} > syn/p12.matches && ${to_matches_23} > syn/p23.matches && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/p12.matches syn/p23.matches --fixed syn/view1.tif --dem syn/truth.dem.tif -o adj"
  STDERR_MATCH "rpc-adjust: 800 tracks, 1600 observations, model affine: rms [1-9][0-9.]* px before, [0-9.e-]+ px after.*\nrpc-adjust: tracks by length 2:800@SEMI@ 1600 observations weighted by their sigma, 0 at 0.03536 px@SEMI@ weights reference sigma 0.03536 px / sigma.*\nrpc-adjust: image2 syn/view2.tif: 800 observations, tracks by length 2:800, median sigma 0.03536 px"
  CHECK_FILE adj/rpc.residuals
  FILE_MATCH "# rms_after_px: (0\\.00[0-9]*|[0-9.]+e-[0-9]+)\n")
# Refused with the file and line, nothing written: a track seen in one view, nan in x but not in y.
tpkit_tool_test(rpc-adjust.track-of-one-view
  COMMAND "${synth_biased} && ${blank} | awk '!/^#/ && ++n == 7 { $4 = $5 = \"nan\" } { print }' > syn/one.tracks && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/one.tracks -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: syn/one.tracks:[0-9]+: .*1 view" NO_FILE adj)
tpkit_tool_test(rpc-adjust.nan-in-x-only
  COMMAND "${synth_biased} && ${blank} | awk '!/^#/ && ++n == 1 { $2 = \"nan\" } { print }' > syn/half.tracks && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/half.tracks -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: syn/half.tracks:[0-9]+: .*x1 nan" NO_FILE adj)
# --fixed takes one image per occurrence: 'rpc-adjust A --fixed A B C' fixed B and C too (CLI11 gave the
# option every value after it), leaving no image to adjust
tpkit_tool_test(rpc-adjust.fixed-takes-one-image
  COMMAND "${synth_biased} && rpc-adjust syn/view1.tif --fixed syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks --model shift -o adj"
  STDERR_MATCH "image1 syn/view1.tif \\(fixed\\): .*\nrpc-adjust: image2 syn/view2.tif: .*\nrpc-adjust: image3 syn/view3.tif: ")
# Ground points in GIS forms beside ground.points (issue 25): same points, same values, the CSV's sidecars.
tpkit_tool_test(rpc-adjust.ground-gis-forms
  COMMAND "${synth_biased} && ${adjust} --crs utm -o adj && paste <(grep -v '^#' adj/ground.points) <(tail -n +2 adj/ground.csv | tr ',' ' ') | awk '{ for (k = 1 @SEMI@ k <= 8 @SEMI@ k++) if ($k != $(k + 8)) bad++ } END { print NR, bad + 0 }' && test $(grep -c '\"type\": \"Feature\"' adj/ground.geojson) = $(grep -vc '^#' adj/ground.points) && cat adj/ground.csvt && grep -o 'EPSG\",\"326[0-9][0-9]' adj/ground.prj"
  STDOUT_MATCH "^[1-9][0-9]* 0\nInteger,CoordX,CoordY,CoordZ,Real,Integer,Real,Integer\nEPSG\",\"32631\n$"
  CHECK_FILE adj/ground.geojson
  FILE_MATCH "\"type\": \"FeatureCollection\".*\"projected_crs\": \"EPSG:32631 ")
# Ground control (issue 25): a triplet with a bias on EVERY view, no view fixed; 5 control points (ground
# sigma 0.3 m, image sigma 0.2 px, noise of those sigmas added) and 20 check points from the truth
# (bench/gcp_from_truth.awk), left out of the tie tracks. The check points, intersected on the adjusted
# models, are within 0.5 m of the truth horizontally and vertically (metres before: the biased models).
set(synth_gcp "tp-synth -o syn --size 256 --points 300 --rpc-bias 1:4,-3,0.002,-0.001 --rpc-bias 2:-5,2,0.001,0.002 --rpc-bias 3:3,5,-0.002,0.001 > /dev/null")
set(make_gcp "awk -v TIES=syn/ties.tracks -f $SRC/bench/gcp_from_truth.awk")
set(adjust_gcp "rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/ties.tracks")
set(read_accuracy "awk '/^# check_(before|after)_rmse_[hv]_m:/ { sub(/^# /, \"\") @SEMI@ sub(/:/, \"\") @SEMI@ v[$1] = $2 } END { ok = v[\"check_after_rmse_h_m\"] < 0.5 && v[\"check_after_rmse_v_m\"] < 0.5 && v[\"check_before_rmse_v_m\"] > 2 @SEMI@ print (ok ? \"accuracy ok\" : \"accuracy off\"), v[\"check_after_rmse_h_m\"], v[\"check_after_rmse_v_m\"] }' adj/accuracy")
tpkit_tool_test(rpc-adjust.gcp-check-points
  COMMAND "${synth_gcp} && ${make_gcp} syn/truth.tracks > syn/points.gcp && ${adjust_gcp} --gcp syn/points.gcp -o adj && ${read_accuracy}"
  STDOUT_MATCH "^accuracy ok "
  STDERR_MATCH "rpc-adjust: --gcp: the control points agree with the tie points: rms after [0-9.e-]+ px with the GCPs, [0-9.e-]+ px without .*\nrpc-adjust: control points \\(5 of 5 intersected\\): before RMSE horizontal [0-9.]+ m, vertical [0-9.]+ m, CE90 [0-9.]+ m, LE90 [0-9.]+ m@SEMI@ after .*\nrpc-adjust: check points \\(20 of 20 intersected\\): before RMSE horizontal "
  CHECK_FILE adj/accuracy
  FILE_MATCH "^# tpkit accuracy 1\n.*# columns: id role image x y sigma_px dx_before dy_before dx_after dy_after e_before n_before u_before e_after n_after u_after\n.*# check_after_n: 20\n")
# ASP's .gcp form (id lat lon height sigmas, then image col row sigmas): 5 truth points, every one a control
# point, the images named by file name alone; the adjustment agrees with them.
set(asp_gcp "awk '/^# columns:/ { for (i = 3@SEMI@ i <= NF@SEMI@ ++i) c[$i] = i - 2 } /^#/ { next } NR % 60 == 0 { printf \"%d %.10f %.10f %.3f 0.3 0.3 0.3\", $1, $c[\"lat\"], $c[\"lon\"], $c[\"h\"] @SEMI@ for (v = 1@SEMI@ v <= 3@SEMI@ ++v) printf \" view%d.tif %.3f %.3f 0.2 0.2\", v, $c[\"x\" v], $c[\"y\" v] @SEMI@ print \"\" }' syn/truth.tracks")
tpkit_tool_test(rpc-adjust.gcp-asp-form
  COMMAND "${synth_gcp} && ${asp_gcp} > syn/asp.gcp && test $(wc -l < syn/asp.gcp) -ge 4 && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks --gcp syn/asp.gcp --strict -o adj"
  STDERR_MATCH "the control points agree with the tie points: .*\nrpc-adjust: control points \\([0-9]+ of [0-9]+ intersected\\): before RMSE horizontal [0-9.]+ m, vertical [1-9][0-9.]* m, CE90 [0-9.]+ m, LE90 [0-9.]+ m@SEMI@ after RMSE horizontal 0\\.0[0-9]* m, vertical 0\\.0[0-9]* m"
  CHECK_FILE adj/accuracy FILE_MATCH "# control_after_n: [4-9]\n")
# A control point 20 m off in the east: a warning with the figures (the point, its normalized residual,
# metres); --strict refuses the run and writes nothing.
tpkit_tool_test(rpc-adjust.gcp-contradicting
  COMMAND "${synth_gcp} && ${make_gcp} BLUNDER=20 syn/truth.tracks > syn/points.gcp && ${adjust_gcp} --gcp syn/points.gcp -o adj 2> log && grep -c 'warning: --gcp: the control points contradict the tie points: rms after [0-9.e-]* px with the GCPs, [0-9.e-]* px without (over the [0-9]* tracks neither flags)@SEMI@ largest normalized GCP residual [0-9.]* sigma at point [0-9]* (adjusted minus given: e -*[1-9][0-9.]* m' log && ${adjust_gcp} --gcp syn/points.gcp --strict -o adj2"
  EXPECT_FAIL STDOUT_MATCH "^1\n$" STDERR_MATCH "rpc-adjust: --gcp: the control points contradict the tie points \\(--strict\\): rms after" NO_FILE adj2)
# Bad GCP files: an image that is none of the images, a measurement off its image, a malformed ASP line:
# file:line, exit 1, nothing written.
tpkit_tool_test(rpc-adjust.gcp-unknown-image
  COMMAND "${synth_gcp} && ${make_gcp} syn/truth.tracks | sed '2s/view1.tif/other.tif/' > syn/points.gcp && ${adjust_gcp} --gcp syn/points.gcp -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: syn/points.gcp:[0-9]+: control point [0-9]+: image 'other.tif' is not one of the images given" NO_FILE adj)
tpkit_tool_test(rpc-adjust.gcp-off-image
  COMMAND "${synth_gcp} && printf '1 43.3 5.4 100 1 1 1 view1.tif 10 20 0.2 0.2\\n2 43.3 5.4 100 1 1 1 view2.tif 300 20 0.2 0.2\\n' > syn/bad.gcp && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks --gcp syn/bad.gcp -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: syn/bad.gcp:2: control point 2: \\(300, 20\\) is off syn/view2.tif \\(256 x 256 pixels\\)" NO_FILE adj)
tpkit_tool_test(rpc-adjust.gcp-malformed-asp
  COMMAND "${synth_gcp} && printf '# ASP\\n1 43.3 5.4 100 1 1 1 view1.tif 10 20 0.2\\n' > syn/bad.gcp && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks --gcp syn/bad.gcp -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: syn/bad.gcp:2: 11 fields: an ASP GCP line is" NO_FILE adj)
# issue 27: residuals.svg renders (rsvg-convert), every mark inside its panel, one exaggeration for
# every panel, each panel's RMSE (the before row, then the after row) equal to rpc.residuals' summary lines
tpkit_tool_test(rpc-adjust.figure-renders
  COMMAND "${synth_biased} && ${adjust} --model affine -o adj && bash $SRC/tests/tools/figure_check.sh adj/residuals.svg --field --rmse adj/rpc.residuals image1_rms_before_px image2_rms_before_px image3_rms_before_px image1_rms_after_px image2_rms_after_px image3_rms_after_px && grep -c 'stroke=\"#e4002b\"' adj/residuals.svg"
  STDOUT_MATCH "exaggeration: vectors ×[0-9.e+]+\nrmse: [^\n]+\nfigure ok: [0-9]+x[0-9]+\n[1-9][0-9]*\n")
# Per-view blunders (issue 51): a 6-view block (views 2-6 biased) whose every 4th track of 3 or more views
# has one view moved 12 px (tests/tools/blunder_views.awk, which writes which): exactly those views are
# dropped (column dropped of rpc.residuals), every track is kept (none flagged), and the adjusted models
# put the truth ground points at the truth heights (tp-ground on the clean truth tracks).
set(synth_block "tp-synth -o blk --views 6 --size 512 --random-bias 5 --seed 3 > /dev/null")
set(block_views "blk/view1.tif blk/view2.tif blk/view3.tif blk/view4.tif blk/view5.tif blk/view6.tif")
set(block_rpc "--rpc blk/view2.tif=adj/view2_rpc.txt --rpc blk/view3.tif=adj/view3_rpc.txt --rpc blk/view4.tif=adj/view4_rpc.txt --rpc blk/view5.tif=adj/view5_rpc.txt --rpc blk/view6.tif=adj/view6_rpc.txt")
set(dropped_views "awk '/^# columns:/ { for (i = 3@SEMI@ i <= NF@SEMI@ i++) c[$i] = i - 2 } /^#/ { next } $c[\"dropped\"] == 1 { print $c[\"track\"], $c[\"image\"] }' adj/rpc.residuals | sort > got.txt && sort blunders.txt > want.txt && test -s want.txt && cmp got.txt want.txt && echo \"dropped $(wc -l < got.txt) of $(wc -l < want.txt): the moved views\"")
set(block_heights "awk 'NR == FNR { if (!/^#/) h[$1] = $19 @SEMI@ next } !/^#/ { d = $4 - h[$1] @SEMI@ s += d * d @SEMI@ n++ } END { r = sqrt(s / n) @SEMI@ print (r < 0.25 ? \"heights ok\" : \"heights off\"), n, r }' blk/truth.tracks g.points")
tpkit_tool_test(rpc-adjust.blunder-views-dropped
  COMMAND "${synth_block} && awk -f $SRC/tests/tools/blunder_views.awk blk/truth.tracks > bad.tracks && rpc-adjust ${block_views} --tracks bad.tracks --fixed blk/view1.tif --dem blk/truth.dem.tif -o adj && ${dropped_views} && tp-ground ${block_views} --tracks blk/truth.tracks ${block_rpc} -o g.points && ${block_heights}"
  STDOUT_MATCH "^dropped 166 of 166: the moved views\nheights ok 2000 "
  STDERR_MATCH "rpc-adjust: 166 views dropped as blunders from 166 tracks of 3 or more views \\(166 of them kept"
  CHECK_FILE adj/rpc.residuals
  FILE_MATCH "# columns: track image x y dx_before dy_before dx_after dy_after flagged sigma dropped\n.*# flagged_tracks: 0\n# dropped_views: 166\n# tracks_with_dropped_views: 166\n")
# Height priors at the default --dem-sigma (issue 51): its sigma is estimated from the data and said; a
# DEM 2 m noisy and 3 m off (bench_dem_reference) agrees with the tie points (--strict), a DEM 200 m off
# is refused (the biases it forces, 250 px, are no delivered model's).
if(TPKIT_BENCH)
tpkit_tool_test(rpc-adjust.dem-sigma-estimated
  COMMAND "${synth_biased} && bench_dem_reference syn/truth.dem.tif ref3.tif 2 2 ellipsoid 1 0 0 3 && bench_dem_reference syn/truth.dem.tif ref200.tif 2 2 ellipsoid 1 0 0 200 && ${adjust} --dem ref3.tif --strict -o adj && ${adjust} --dem ref200.tif -o adj3"
  EXPECT_FAIL
  STDERR_MATCH "--dem ref3.tif: sigma [0-9.]+ m estimated from the data \\(prior minus free height over [0-9]+ tracks: median -?[0-9.]+ m, NMAD [0-9.]+ m.*--dem ref3.tif agrees with the tie points: .*rpc-adjust: --dem ref200.tif contradicts the tie points: rms after [^\n]* median 19[0-9.]+ m \\(3 NMAD [0-9.]+ m@SEMI@ the biases it forces: [0-9.]+ px [^\n]*the biases it forces are beyond any delivered model's"
  NO_FILE adj3)
endif()
