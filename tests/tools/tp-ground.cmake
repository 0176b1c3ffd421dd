# tp-ground: the truth tracks of an unbiased synthetic scene land on the truth ground points.
tpkit_tool_test(tp-ground.truth-heights
  COMMAND "tp-synth -o syn --size 512 --points 300 && tp-ground syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks -o g.points && paste <(grep -v '^#' syn/truth.tracks) <(grep -v '^#' g.points) | awk '{ d = $13 - $17 @SEMI@ s += d * d @SEMI@ e = ($11 - $15) * 81000 @SEMI@ t += e * e @SEMI@ n++ } END { print (sqrt(s / n) < 0.01 && sqrt(t / n) < 0.01 ? \"ground ok\" : \"ground off\"), sqrt(s / n), sqrt(t / n) }'"
  STDOUT_MATCH "^ground ok "
  CHECK_FILE g.points
  FILE_MATCH "^# tpkit ground 1\n.*# crs: EPSG:4979 .*# model1: syn/view1.tif \\(tiff\\)\n.*# columns: track lon lat h sigma_h views rms_px\n")
tpkit_tool_test(tp-ground.ecef
  COMMAND "tp-synth -o syn --size 256 --relief 20 --points 50 && tp-ground syn/view1.tif syn/view2.tif --tracks syn/truth.tracks --crs ecef -o g.points"
  EXPECT_FAIL STDERR_MATCH "tp-ground: syn/truth.tracks: image3 'view3.tif' is not one of the images given")
tpkit_tool_test(tp-ground.ecef-coordinates
  COMMAND "tp-synth -o syn --size 256 --relief 20 --points 50 && tp-ground syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks --crs ecef -o g.points && grep -v '^#' g.points | awk '{ r = sqrt($2^2 + $3^2 + $4^2) @SEMI@ if (r < 6.36e6 || r > 6.37e6) bad++ } END { print bad + 0 }'"
  STDOUT_MATCH "^0\n"
  CHECK_FILE g.points
  FILE_MATCH "# crs: EPSG:4978 .*# columns: track X Y Z sigma_h views rms_px\n")
tpkit_tool_test(tp-ground.bad-crs
  COMMAND "tp-ground a.tif b.tif --tracks t --crs lambert"
  EXPECT_FAIL STDERR_MATCH "^tp-ground: --crs: expected geographic, utm or ecef")
