# tp-ortho: orthos of real crops checked by GDAL (gdalinfo reads the CRS and the geotransform the tool
# printed; gdalwarp -rpc on the same grid agrees within 1 grey level on 99% of the pixels valid in both);
# orthos of one run share one grid, and --compare measures a shift made on purpose; bad input and
# contradicting options are one-line errors with no output.
set(_jax "$SHARED/data/wv3-jacksonville")
set(_mars "$SHARED/data/pleiades-marseille")
set(_gdal "bash $SRC/tests/tools/tp-ortho-gdal.sh")
# gdalinfo: EPSG:32617 and the corner, size and pixel the tool says (its summary line "grid ...")
tpkit_tool_test(tp-ortho.gdalinfo-reads-the-grid
  COMMAND "tp-ortho ${_jax}/JAX_068_004_RGB.tif --dem ${_jax}/lidar_dsm_utm17n.tif --threads 2 -o o.tif 2> log && ${_gdal} info o.tif > gi && sed -nE 's/.*grid (EPSG:[0-9]+) .*, ([0-9]+) x ([0-9]+) px of ([0-9.]+) m, corner ([-0-9.e]+) ([-0-9.e]+)$/\\1 \\2 \\3 \\5 \\6 \\4/p' log > said && paste -d ' ' gi said | awk '{ ok = $1 == $7 && $2 == $8 && $3 == $9 && ($4 - $10) ^ 2 < 1e-12 && ($5 - $11) ^ 2 < 1e-12 && ($6 - $12) ^ 2 < 1e-18@SEMI@ print $1, ($2 * $6 > 200 ? \"wide\" : \"narrow\"), (ok ? \"same\" : \"differs\") }'"
  STDOUT_MATCH "^EPSG:32617 wide same\n$")
# gdalwarp -rpc on the same grid, image and lidar DSM: within 1 grey level on >= 99% of the pixels
tpkit_tool_test(tp-ortho.agrees-with-gdalwarp
  COMMAND "tp-ortho -q ${_jax}/JAX_068_004_RGB.tif --dem ${_jax}/lidar_dsm_utm17n.tif --threads 2 -o o.tif && ${_gdal} agree o.tif ${_jax}/JAX_068_004_RGB.tif -to RPC_DEM=${_jax}/lidar_dsm_utm17n.tif | awk '{ v = $1 + 0@SEMI@ print (v >= 99 ? \"agree\" : $0), ($NF > 100000 ? \"many\" : $NF) }'"
  STDOUT_MATCH "^agree many\n$")
# one grid for a run: three orthos of the same size and corner; a 16-bit image stays 16-bit
tpkit_tool_test(tp-ortho.one-grid-per-run
  COMMAND "tp-ortho -q ${_mars}/img_01.tif ${_mars}/img_02.tif ${_mars}/img_03.tif --height 150 --gsd 1 --threads 2 -o out && for f in out/img_01.ortho.tif out/img_02.ortho.tif out/img_03.ortho.tif@SEMI@ do ${_gdal} info $f@SEMI@ done | sort -u | wc -l && gdalinfo out/img_02.ortho.tif | grep -c 'Type=UInt16'"
  STDOUT_MATCH "^1\n1\n$")
# --compare: an ortho against itself is not shifted; a crop of img_01 from pixel (3, 2) given img_01's own
# model (--rpc) is shifted by what the model says: it shows at ground point G (img_01's pixel p) what
# img_01 shows at p + (3, 2), i.e. at G' = localize(p + (3, 2)); the shift expected is G - G' in grid pixels
# (tp-rpc, at the image's centre; the model is affine to 0.001 px over the crop), measured to 0.05 px
tpkit_tool_test(tp-ortho.compare-measures-a-known-shift
  COMMAND "tp-rpc -q crop ${_mars}/img_01.tif --window 3 2 1021 1022 -o c.tif && tp-ortho -q ${_mars}/img_01.tif c.tif --rpc c.tif=${_mars}/img_01.tif --height 150 --gsd 0.5 -o out && tp-ortho -q --compare out/img_01.ortho.tif out/img_01.ortho.tif out/c.ortho.tif -o t && printf '512 512 150\\n515 514 150\\n' | tp-rpc -q localize ${_mars}/img_01.tif --crs utm | awk 'NR == 1 { e = $1@SEMI@ n = $2 } NR == 2 { print (e - $1) / 0.5, -(n - $2) / 0.5 }' > expected && grep -v '^#' t | awk -v want=\"$(cat expected)\" 'BEGIN { split(want, x, \" \") } { ok = ($5 - ($1 == 1 && $2 == 2 ? 0 : x[1])) ^ 2 + ($6 - ($1 == 1 && $2 == 2 ? 0 : x[2])) ^ 2 < 0.05 ^ 2@SEMI@ print $1, $2, ($3 >= 10 ? \"tiles\" : $3), (ok ? \"as expected\" : $5 \" \" $6 \" against \" want) }'"
  STDOUT_MATCH "^1 2 tiles as expected\n1 3 tiles as expected\n2 3 tiles as expected\n$")
tpkit_tool_test(tp-ortho.compare-other-grids
  COMMAND "tp-ortho -q ${_mars}/img_01.tif --height 150 --gsd 1 -o a.tif && tp-ortho -q ${_mars}/img_01.tif --height 150 --gsd 2 -o b.tif && tp-ortho --compare a.tif b.tif -o t"
  EXPECT_FAIL STDERR_MATCH "tp-ortho: b.tif: not on the grid of a.tif" NO_FILE t)
# errors: one line naming the option or file, no output
tpkit_tool_test(tp-ortho.needs-heights
  COMMAND "tp-ortho ${_mars}/img_01.tif -o o.tif@SEMI@ echo exit $?"
  STDOUT_MATCH "exit 2" STDERR_MATCH "give the heights: --dem FILE or --height H")
tpkit_tool_test(tp-ortho.like-goes-alone
  COMMAND "tp-ortho ${_mars}/img_01.tif --height 100 --like x.tif --gsd 2 -o o.tif@SEMI@ echo exit $?"
  STDOUT_MATCH "exit 2" STDERR_MATCH "--like takes the grid of an ortho")
tpkit_tool_test(tp-ortho.bad-dem
  COMMAND "echo not a tiff > dem.tif && tp-ortho ${_mars}/img_01.tif --dem dem.tif -o out"
  EXPECT_FAIL STDERR_MATCH "tp-ortho: dem.tif" NO_FILE out/img_01.ortho.tif)
tpkit_tool_test(tp-ortho.no-model
  COMMAND "tp-ortho -q ${_mars}/img_01.tif --height 150 --gsd 4 -o a.tif && tp-ortho a.tif --height 150 -o b.tif"
  EXPECT_FAIL STDERR_MATCH "a.tif: no RPC model" NO_FILE b.tif)
tpkit_tool_test(tp-ortho.grid-misses-the-image
  COMMAND "tp-ortho ${_mars}/img_01.tif --height 150 --bounds 600000 4700000 600100 4700100 -o o.tif"
  EXPECT_FAIL STDERR_MATCH "img_01.tif: no pixel of the grid sees this image" NO_FILE o.tif)
tpkit_tool_test(tp-ortho.geographic-crs-refused
  COMMAND "tp-ortho ${_mars}/img_01.tif --height 150 --crs EPSG:4326 -o o.tif@SEMI@ echo exit $?"
  STDOUT_MATCH "exit 2" STDERR_MATCH "--crs EPSG:4326: not a projected CRS")
# --occluded nodata on a crop 27 degrees off nadir over the lidar DSM: part of the grid hidden from the view
# (behind the buildings, and their walls), every other pixel as the ortho that keeps them has it (--compare
# of the two: no shift)
tpkit_tool_test(tp-ortho.true-ortho-hides-ground
  COMMAND "tp-ortho -q ${_jax}/JAX_068_020_RGB.tif --dem ${_jax}/lidar_dsm_utm17n.tif --threads 2 -o keep.tif && tp-ortho ${_jax}/JAX_068_020_RGB.tif --dem ${_jax}/lidar_dsm_utm17n.tif --like keep.tif --occluded nodata --threads 2 -o true.tif 2> log && sed -nE 's/.* ([0-9.]+)% hidden from the view.*/\\1/p' log | awk '{ print ($1 >= 1 && $1 <= 30 ? \"some hidden\" : $1) }' && tp-ortho -q --compare keep.tif true.tif --tile 64 --min-valid 0.5 | grep -v '^#' | awk '{ print ($5 ^ 2 + $6 ^ 2 < 0.01 ^ 2 ? \"same pixels\" : $5 \" \" $6) }'"
  STDOUT_MATCH "^some hidden\nsame pixels\n$")
tpkit_tool_test(tp-ortho.occluded-needs-a-dem
  COMMAND "tp-ortho ${_mars}/img_01.tif --height 100 --occluded nodata -o o.tif@SEMI@ echo exit $?"
  STDOUT_MATCH "exit 2" STDERR_MATCH "--occluded nodata needs a surface that can hide the ground: --dem" NO_FILE o.tif)
tpkit_tool_test(tp-ortho.wall-slope-goes-with-occluded
  COMMAND "tp-ortho ${_jax}/JAX_068_020_RGB.tif --dem ${_jax}/lidar_dsm_utm17n.tif --wall-slope 45 -o o.tif@SEMI@ echo exit $?"
  STDOUT_MATCH "exit 2" STDERR_MATCH "--wall-slope goes with --occluded nodata" NO_FILE o.tif)
# True orthos of a city have holes in every 128-px tile: the default compare measures nothing and says how to
tpkit_tool_test(tp-ortho.compare-true-orthos-hint
  COMMAND "tp-ortho -q ${_jax}/JAX_068_001_RGB.tif ${_jax}/JAX_068_003_RGB.tif --dem ${_jax}/lidar_dsm_utm17n.tif --occluded nodata --threads 2 -o t 2> /dev/null && tp-ortho -q --compare t/JAX_068_001_RGB.ortho.tif t/JAX_068_003_RGB.ortho.tif -o a 2> err@SEMI@ cat err && grep -v '^#' a | awk '{ print $11 }' && tp-ortho -q --compare t/JAX_068_001_RGB.ortho.tif t/JAX_068_003_RGB.ortho.tif --tile 64 -o b && grep -v '^#' b | awk '{ print ($3 >= 2 ? \"measured on 64-px tiles\" : $3) }'"
  STDOUT_MATCH "holes in every tile: true orthos of a city need --tile 64 or --min-valid 0.5.*\nnan\nmeasured on 64-px tiles\n$")
