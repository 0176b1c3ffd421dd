# NITF images (NITF 2.1, uncompressed and JPEG 2000) as tools read and write them.
# The WorldView-3 crops of ../shared/data/nitf-wv3: tp-rpc projects ground points to the pixels GDAL's RPC
# transformer gives for the same files (gdaltransform -rpc -i, GDAL 3.6.2, computed once and stored here:
# lon lat h, then GDAL's pixel less 0.5, as GDAL counts from the top-left corner of the top-left pixel and
# tpkit from its centre), to 1e-6 px.
set(_wv3 "$SHARED/data/nitf-wv3")
set(_mars "$SHARED/data/pleiades-marseille")
set(_gdal_wv3_20 "-58.5258247 -34.5556580 -50 0.011264842 -0.010684622\\n-58.5274411 -34.5556560 20 498.996463597 -0.015651330\\n-58.5254210 -34.5541821 80 0.007753017 499.014732457\\n-58.5270370 -34.5541801 150 499.001656923 499.010460052\\n-58.5264915 -34.5549192 31 249.996564797 249.987913480\\n-58.5261203 -34.5545186 0 123.009811623 387.007621567")
set(_gdal_wv3_30 "-58.5225071 -34.5667244 -50 -0.002925727 -0.001212669\\n-58.5242278 -34.5668472 20 499.006757436 0.001846712\\n-58.5222380 -34.5655412 80 0.003317209 499.012553082\\n-58.5239582 -34.5656640 150 498.999445413 499.013183188\\n-58.5232742 -34.5661289 31 249.997783356 249.998657239\\n-58.5228640 -34.5656092 0 123.003096510 387.000661733")
foreach(_f wv3_20 wv3_30)
  tpkit_tool_test(nitf.${_f}-projects-as-gdal
    COMMAND "printf -- '${_gdal_${_f}}\\n' > ref && awk '{ print $1, $2, $3 }' ref | tp-rpc -q project ${_wv3}/${_f}.NTF | paste -d ' ' ref - | awk '{ d = sqrt(($4 - $6) ^ 2 + ($5 - $7) ^ 2)@SEMI@ if (d > m) m = d@SEMI@ n++ } END { printf \"%d points, max %s\\n\", n, (m <= 1e-6 ? \"<= 1e-6 px\" : m) }'"
    STDOUT_MATCH "^6 points, max <= 1e-6 px\n$" )
endforeach()
# The Marseille triplet converted to NITF (uncompressed in blocks of 300 px with pad pixels, and lossless
# JPEG 2000 in tiles of 256 px) gives tp-match the same matches as the GeoTIFFs it came from, although the
# models went through the RPC00B TRE's fixed precision (the crop says by how much).
tpkit_tool_test(nitf.triplet-same-matches
  COMMAND "for i in 1 2 3@SEMI@ do tp-rpc crop ${_mars}/img_0$i.tif --block 300 -o n$i.ntf 2>> crop.log && tp-rpc -q crop ${_mars}/img_0$i.tif --compression j2k --block 256 -o j$i.ntf || exit 1@SEMI@ done && for p in '1 2' '2 3'@SEMI@ do set -- $p@SEMI@ tp-match ${_mars}/img_0$1.tif ${_mars}/img_0$2.tif --threads 2 -o t.m 2>/dev/null && tp-match n$1.ntf n$2.ntf --threads 2 -o n.m 2>/dev/null && tp-match j$1.ntf j$2.ntf --threads 2 -o j.m 2>/dev/null || exit 1@SEMI@ grep -v '^#' t.m > t@SEMI@ grep -v '^#' n.m | cmp -s - t && grep -v '^#' j.m | cmp -s - t && echo \"pair $1-$2: $(wc -l < t) matches, the same\"@SEMI@ done@SEMI@ grep -c 'RPC00B precision: 0.00[0-9]* px at most' crop.log"
  STDOUT_MATCH "^pair 1-2: [0-9]+ matches, the same\npair 2-3: [0-9]+ matches, the same\n3\n$")
# A NITF image without an RPC TRE has no model (a clear error, as for a GeoTIFF without the tag); a
# NITF output takes --compression and --block, a GeoTIFF does not.
tpkit_tool_test(nitf.image-without-a-model
  COMMAND "LC_ALL=C sed 's/RPC00B/XYZ00B/' ${_wv3}/wv3_20.NTF > plain.ntf && echo '-58.52 -34.55 20' | tp-rpc project plain.ntf"
  EXPECT_FAIL STDERR_MATCH "tp-rpc: plain.ntf: no RPC model: no RPC00B or RPC00A TRE, none of .* beside it")
tpkit_tool_test(nitf.compression-needs-a-nitf-output
  COMMAND "tp-rpc crop ${_wv3}/wv3_20.NTF --window 0 0 10 10 --compression j2k -o c.tif @SEMI@ echo exit $?"
  STDOUT_MATCH "exit 2" STDERR_MATCH "--compression and --block go with a NITF output")
tpkit_tool_test(nitf.truncated-image
  COMMAND "head -c 300000 ${_wv3}/wv3_20.NTF > cut.ntf && tp-match cut.ntf ${_wv3}/wv3_30.NTF -o m.matches"
  EXPECT_FAIL STDERR_MATCH "tp-match: cut.ntf: truncated: the image data ends at byte 501958, the file has 300000" NO_FILE m.matches)
