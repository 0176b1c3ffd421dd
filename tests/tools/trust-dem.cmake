# Trust campaign (issue 50), group "dem": reference DEMs through tp-ground --compare/--align, tp-rpc --dem and
# rpc-adjust --dem, which share one reader (ReferenceDem). What needs a DEM no tool writes (vertical units,
# "-3.4e+38" float nodata, a huge strip or tile) is in tests/unit/ground/reference_dem_trust_test.cpp.
set(dem_small "tp-synth -o syn --size 64 --gsd 20 --points 40 > /dev/null")
set(dem_scene "tp-synth -o syn --size 192 --gsd 20 --relief 300 --points 300 > /dev/null")
set(dem_ground "tp-ground syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks")

# Item 13: PROJ's optional-grid prefix '@' made a missing grid silently no grid (dz against the ellipsoid,
# rc 0); the datum option is refused, naming it, and no output is left.
tpkit_tool_test(trust-dem.datum-optional-grid-refused
  COMMAND "${dem_small} && ${dem_ground} --compare syn/truth.dem.tif --dem-datum @missing.gtx --dz dz.txt -o g.points"
  EXPECT_FAIL STDERR_MATCH "tp-ground: --dem-datum \\(for syn/truth.dem.tif\\) '@missing.gtx': neither ellipsoid, egm96, egm2008 nor a grid's file name"
  NO_FILE dz.txt)
# Item 13: '+multiplier=1000' after a grid was pasted into the PROJ definition (undulations x 1000); tp-rpc
# --dem (the same reader) refuses it.
tpkit_tool_test(trust-dem.datum-proj-parameters-refused
  COMMAND "${dem_small} && echo '32 32' | tp-rpc localize syn/view1.tif --dem syn/truth.dem.tif --dem-datum 'egm96_15.gtx +multiplier=1000'"
  EXPECT_FAIL STDERR_MATCH "tp-rpc: --dem-datum \\(for syn/truth.dem.tif\\) 'egm96_15.gtx \\+multiplier=1000': neither ellipsoid")
# Item 8: a DEM that reaches none of the points (the scene's DEM of another place) gave rc 0 and a dz file
# of zero counts; it is refused as rpc-adjust refuses it.
tpkit_tool_test(trust-dem.compare-dem-off-the-points
  COMMAND "${dem_small} && tp-synth -o far --size 64 --gsd 20 --points 10 --origin 10,10,0 > /dev/null && ${dem_ground} --compare far/truth.dem.tif --dz dz.txt -o g.points"
  EXPECT_FAIL STDERR_MATCH "tp-ground: far/truth.dem.tif: none of the [0-9]+ points has a height on it" NO_FILE dz.txt)

# These need the benchmark program bench_dem_reference (a UTM DEM with EGM96 vertical keys, as GDAL writes
# EPSG:32631+5773; not built in the sanitizer build).
if(TPKIT_BENCH)
# Item 7: without --dem-datum the DEM's vertical keys (EGM96) are used: the truth points are on it (|median
# dz| < 0.1 m), where they were the EGM96 undulation (49.4 m) above it, and the dem-dz file says egm96.
tpkit_tool_test(trust-dem.compare-datum-from-keys
  COMMAND "${dem_scene} && bench_dem_reference syn/truth.dem.tif ref.tif 30 0 egm96 > /dev/null && ${dem_ground} --compare ref.tif --dz dz.txt -o /dev/null 2>&1 | grep 'dz all'"
  STDOUT_MATCH "dz all: [0-9]+ points, dz median -?0\\.0[0-9]* m"
  CHECK_FILE dz.txt FILE_MATCH "# dem: ref.tif \\(EPSG:32631, posting 30 m, heights above egm96\\)")
# Item 7: --align likewise (it gave an up shift of 52 m for 3 m).
tpkit_tool_test(trust-dem.align-datum-from-keys
  COMMAND "${dem_scene} && bench_dem_reference syn/truth.dem.tif refs.tif 30 0 egm96 1 8 -5 3 > /dev/null && ${dem_ground} --align refs.tif -o /dev/null 2>&1 | grep 'shift east'"
  STDOUT_MATCH "shift east north up 7\\.[89][0-9]* -5\\.[123][0-9]* 3\\.?[0-9]* m ")
# Item 7: a --dem-datum that disagrees with the keys is refused, naming both.
tpkit_tool_test(trust-dem.datum-disagreeing-with-keys-refused
  COMMAND "${dem_scene} && bench_dem_reference syn/truth.dem.tif ref.tif 30 0 egm96 > /dev/null && ${dem_ground} --compare ref.tif --dem-datum ellipsoid --dz dz.txt -o g.points"
  EXPECT_FAIL STDERR_MATCH "tp-ground: ref.tif: --dem-datum ellipsoid disagrees with the GeoTIFF keys' vertical CRS EPSG:5773 \\(egm96\\): leave --dem-datum out"
  NO_FILE dz.txt)
endif()
