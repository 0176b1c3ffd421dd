# tp-rpc: points through one RPC model, streamed. Localize then project returns the pixel over the
# Marseille model's image and heights (1e-6 px); localize onto a tp-synth scene's truth DEM then project
# into another view lands on the truth tracks (0.01 px, mild relief: the DEM is bilinear between samples
# 1 m apart); comment lines and extra columns pass; bad lines are errors with their line and no output.
set(_mars "$SHARED/data/pleiades-marseille")
set(_scene "tp-synth --out s --size 300 --seed 2 --relief 10 --threads 2 --supersample 1 >/dev/null")
tpkit_tool_test(tp-rpc.localize-project-round-trip
  COMMAND "awk 'BEGIN { for (i = 0@SEMI@ i <= 10@SEMI@ i++) for (j = 0@SEMI@ j <= 10@SEMI@ j++) for (h = 50@SEMI@ h <= 350@SEMI@ h += 100) print 102.3 * i, 102.3 * j, h, i \"-\" j }' > px && tp-rpc -q localize ${_mars}/img_01.tif -i px | tp-rpc -q project ${_mars}/img_01.tif | paste -d ' ' px - | awk '{ d = sqrt(($1 - $5) ^ 2 + ($2 - $6) ^ 2)@SEMI@ if (d > m) m = d@SEMI@ n++ } END { printf \"%d points, max %s\\n\", n, (m <= 1e-6 ? \"<= 1e-6 px\" : m) }'"
  STDOUT_MATCH "^484 points, max <= 1e-6 px\n$")
tpkit_tool_test(tp-rpc.dem-lands-on-truth
  COMMAND "${_scene} && grep -v '^#' s/truth.tracks | awk '{ print $2, $3, $4, $5 }' > v12 && tp-rpc -q localize s/view1.tif --dem s/truth.dem.tif -i v12 | tp-rpc -q project s/view2.tif | awk '$1 != \"nan\" { d = sqrt(($1 - $4) ^ 2 + ($2 - $5) ^ 2)@SEMI@ if (d > m) m = d@SEMI@ n++ } $1 == \"nan\" { k++ } END { printf \"%s solved, %d nan, max %s\\n\", (n >= 0.99 * (n + k) ? \"99%\" : n), k, (m <= 0.01 ? \"<= 0.01 px\" : m) }'"
  STDOUT_MATCH "^99% solved, [0-9]+ nan, max <= 0.01 px\n$")
tpkit_tool_test(tp-rpc.comments-and-extra-columns
  COMMAND "${_scene} && printf '# ground\\n5.4 43.3 100 id7 \\tkept\\n\\n' | tp-rpc project s/view1.tif | sed 's/^[-0-9.e]* [-0-9.e]* /X Y /'"
  STDOUT_MATCH "^# ground\nX Y 100 id7 \tkept\n\n$" STDERR_MATCH "project through s/view1.tif \\(tiff\\): 1 points, 2 lines passed through")
tpkit_tool_test(tp-rpc.model-file-same-as-image
  COMMAND "${_scene} && echo '150.5 120.25 60' > p && tp-rpc -q localize s/view1.tif -i p > a && tp-rpc -q localize s/view1_rpc.txt -i p > b && cmp a b && echo same"
  STDOUT_MATCH "^same\n$")
tpkit_tool_test(tp-rpc.bad-line
  COMMAND "${_scene} && printf '5.4 43.3 100\\n5.4 x 100\\n' | tp-rpc project s/view1.tif -o out.txt"
  EXPECT_FAIL STDERR_MATCH "tp-rpc: stdin:2: 'x' is not a finite number" NO_FILE out.txt)
tpkit_tool_test(tp-rpc.too-few-columns
  COMMAND "${_scene} && printf '1 2\\n' > p && tp-rpc localize s/view1.tif -i p -o out.txt"
  EXPECT_FAIL STDERR_MATCH "tp-rpc: p:1: expected 3 numbers, got 2" NO_FILE out.txt)
tpkit_tool_test(tp-rpc.no-model
  COMMAND "${_scene} && echo 5.4 43.3 100 | tp-rpc project s/truth.dem.tif"
  EXPECT_FAIL STDERR_MATCH "s/truth.dem.tif: no RPC model: no tag 50844")
tpkit_tool_test(tp-rpc.dem-needs-localize
  COMMAND "${_scene} && echo '1 2 3' | tp-rpc project s/view1.tif --dem s/truth.dem.tif @SEMI@ echo exit $?"
  STDOUT_MATCH "exit 2" STDERR_MATCH "--dem goes with localize")
tpkit_tool_test(tp-rpc.off-the-dem-marked-nan
  COMMAND "${_scene} && printf '150 150 k1\\n-5000 -5000 k2\\n' | tp-rpc localize s/view1.tif --dem s/truth.dem.tif | awk '{ print $1, $4 }'"
  STDOUT_MATCH "^5\\.[0-9]+ k1\nnan k2\n$" STDERR_MATCH "1 points have no solution and are written as nan@SEMI@ the first: stdin:2: ")
# crop: a window with its model; a ground point projects into the crop at the image's pixel less the
# window's corner; crop needs a window inside the image and a file output
tpkit_tool_test(tp-rpc.crop-keeps-the-geometry
  COMMAND "tp-rpc -q crop ${_mars}/img_01.tif --window 100 200 300 250 -o crop.tif && echo '5.4428 43.2618 150' > g && tp-rpc -q project ${_mars}/img_01.tif -i g > a && tp-rpc -q project crop.tif -i g > b && paste -d ' ' a b | awk '{ printf \"%.9f %.9f\\n\", $1 - $4, $2 - $5 }'"
  STDOUT_MATCH "^100\\.000000000 200\\.000000000\n$")
tpkit_tool_test(tp-rpc.crop-outside-the-image
  COMMAND "tp-rpc crop ${_mars}/img_01.tif --window 900 0 200 10 -o crop.tif"
  EXPECT_FAIL STDERR_MATCH "img_01.tif: the window 900 0 200 10 is not inside the image \\(1024 x 1024\\)" NO_FILE crop.tif)
tpkit_tool_test(tp-rpc.crop-needs-a-file
  COMMAND "tp-rpc crop ${_mars}/img_01.tif --window 0 0 10 10 @SEMI@ echo exit $?"
  STDOUT_MATCH "exit 2" STDERR_MATCH "crop needs -o OUT.tif")
# the OSSIM .geom and GDAL .aux.xml forms: a view's _rpc.txt rewritten by hand in each gives its pixels
tpkit_tool_test(tp-rpc.geom-and-aux-same-as-txt
  COMMAND "bash $SRC/tests/tools/tp-rpc-forms.sh"
  STDOUT_MATCH "^geom: 147 points, same pixels@SEMI@ m.geom \\(geom\\)\naux: 147 points, same pixels@SEMI@ img.tif.aux.xml \\(aux\\)\n$")
# --crs: ground points in UTM (the model centre's zone, 31N at Marseille) or ECEF, read by project and
# written by localize; the values are PROJ's (cct +proj=utm +zone=31 / +proj=cart, WGS84, computed once),
# and the pixels the same as through lon lat h to 1e-5 px (PROJ printed 1e-6 m)
tpkit_tool_test(tp-rpc.crs-utm-and-ecef-as-proj
  COMMAND "printf '5.38 43.30 80\\n5.50 43.22 300\\n' > ll && printf '693046.809404 4796880.750200 80\\n703046.473160 4788280.417277 300\\n' > utm && printf '4628736.756182 435914.329043 4351872.072125\\n4634036.160635 446206.931220 4345550.077421\\n' > xyz && tp-rpc -q project ${_mars}/img_01.tif -i ll > a && tp-rpc -q project --crs utm ${_mars}/img_01.tif -i utm > b && tp-rpc -q project --crs ecef ${_mars}/img_01.tif -i xyz > c && tp-rpc -q localize --crs utm ${_mars}/img_01.tif -i a > u2 && paste -d ' ' a b c u2 utm | awk '{ d = sqrt(($1 - $4) ^ 2 + ($2 - $5) ^ 2) + sqrt(($1 - $7) ^ 2 + ($2 - $8) ^ 2)@SEMI@ e = sqrt(($10 - $13) ^ 2 + ($11 - $14) ^ 2)@SEMI@ if (d > m) m = d@SEMI@ if (e > k) k = e } END { printf \"pixels %s, utm %s\\n\", (m <= 1e-5 ? \"same\" : m), (k <= 1e-5 ? \"as PROJ\" : k) }'"
  STDOUT_MATCH "^pixels same, utm as PROJ\n$")
tpkit_tool_test(tp-rpc.crs-goes-with-points
  COMMAND "tp-rpc crop ${_mars}/img_01.tif --crs utm -o c.tif @SEMI@ echo exit $?"
  STDOUT_MATCH "exit 2" STDERR_MATCH "--crs goes with project and localize")
