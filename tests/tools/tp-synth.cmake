# tp-synth: a small triplet with every file and header; bad options fail with a message and write nothing.
tpkit_tool_test(tp-synth.small-run
  COMMAND "tp-synth --out out --size 256 --relief 20 --points 100 --seed 3 --threads 2 && for f in view1.tif view2.tif view3.tif truth.tracks truth.cameras truth.trifocal scene.params @SEMI@ do test -s out/$f || echo MISSING $f @SEMI@ done && echo records $(grep -vc '^#' out/truth.tracks)"
  STDOUT_MATCH "^records 100\n$"
  CHECK_FILE out/truth.tracks
  FILE_MATCH "^# tpkit tracks 1\n# written-by: tp-synth [0-9]+\\.[0-9]+\\.[0-9]+[^\n]*\n# image1: view1.tif 256 256\n# image2: view2.tif 256 256\n# image3: view3.tif 256 256\n.*# seed: 3\n.*# relief: 20\n.*# columns: track x1 y1 x2 y2 x3 y3 X Y Z lon lat h\n1 [0-9]")
tpkit_tool_test(tp-synth.cameras-file
  COMMAND "tp-synth --out out --size 128 --relief 10 --points 20"
  CHECK_FILE out/truth.cameras
  FILE_MATCH "^# tpkit cameras 1\n.*# seed: 1\n.*# view 1\n[^\n]+\n[^\n]+\n0 0 0 1\n# view 2\n.*# view 3\n")
tpkit_tool_test(tp-synth.trifocal-file
  COMMAND "tp-synth --out out --size 128 --relief 10 --points 20 --camera affine"
  CHECK_FILE out/truth.trifocal
  FILE_MATCH "^# tpkit trifocal 1\n.*# camera: affine\n")
tpkit_tool_test(tp-synth.params-file
  COMMAND "tp-synth --out out --size 128 --relief 12.5 --gsd 0.7 --noise 0 --points 5 --seed 99"
  CHECK_FILE out/scene.params
  FILE_MATCH "seed = 99\nsize = 128\nrelief = 12.5\ngsd = 0.7\ncamera = affine\npoints = 5\nnoise = 0\n")
tpkit_tool_test(tp-synth.perspective-no-trifocal
  COMMAND "tp-synth --out out --size 128 --relief 10 --points 20 --camera perspective && test -s out/truth.cameras"
  NO_FILE out/truth.trifocal)
tpkit_tool_test(tp-synth.same-seed-same-bytes
  COMMAND "tp-synth --out a --size 96 --relief 5 --points 10 --threads 1 && tp-synth --out b --size 96 --relief 5 --points 10 --threads 2 && cmp a/view2.tif b/view2.tif && cmp a/truth.tracks b/truth.tracks && echo identical"
  STDOUT_MATCH "identical")
tpkit_tool_test(tp-synth.negative-size
  COMMAND "tp-synth --out out --size -5"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: .*--size" NO_FILE out)
tpkit_tool_test(tp-synth.unknown-camera
  COMMAND "tp-synth --out out --camera fisheye"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: .*--camera must be affine or perspective" NO_FILE out)
tpkit_tool_test(tp-synth.relief-too-large
  COMMAND "tp-synth --out out --size 64 --relief 500"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: .*relief.*too large" NO_FILE out)
tpkit_tool_test(tp-synth.negative-gsd
  COMMAND "tp-synth --out out --gsd -1"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: .*--gsd" NO_FILE out)
tpkit_tool_test(tp-synth.missing-out
  COMMAND "tp-synth --size 64"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: .*--out")
tpkit_tool_test(tp-synth.out-is-a-file
  COMMAND "echo x > out && tp-synth --out out --size 64 --relief 5 --points 5"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: out: cannot create the folder")
tpkit_tool_test(tp-synth.size-that-cannot-finish
  COMMAND "timeout 10 tp-synth --out out --size 100000"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --size must be between 16 and 40000" NO_FILE out)
# a scene folder is all new or all old: a perspective scene over an affine one leaves no stale tensor,
# and an interrupted run leaves the old files untouched and no temporary files
tpkit_tool_test(tp-synth.no-stale-truth
  COMMAND "tp-synth --out s --size 128 --relief 10 --points 20 --camera affine && test -e s/truth.trifocal && tp-synth --out s --size 128 --relief 10 --points 20 --camera perspective && ls s"
  NO_FILE s/truth.trifocal)
tpkit_tool_test(tp-synth.interrupted-leaves-old-scene
  COMMAND "tp-synth --out s --size 128 --relief 10 --points 20 && cp -r s old && (tp-synth --out s --size 3000 --relief 10 --points 20 --seed 9 & pid=$! @SEMI@ sleep 2 @SEMI@ kill -TERM $pid @SEMI@ wait $pid @SEMI@ echo killed $?) && ls s && test -z \"$(ls s | grep tmp)\" && diff -r old s && echo untouched"
  STDOUT_MATCH "killed 143.*untouched")

# --cross-track: one angle puts the three viewing directions in one plane (det of the three ray directions,
# the cross products of each camera's first two rows, ~ 0); the angle is kept in scene.params
tpkit_tool_test(tp-synth.cross-track-coplanar
  COMMAND "tp-synth --out s --size 160 --points 20 --supersample 1 --cross-track 0 >/dev/null 2>&1 && grep -q '^cross_track = 0$' s/scene.params && awk '!/^#/ && NF==4 {r[k++]=$0} END{for(v=0;v<3;v++){split(r[3*v],a);split(r[3*v+1],b); d[v,1]=a[2]*b[3]-a[3]*b[2]; d[v,2]=a[3]*b[1]-a[1]*b[3]; d[v,3]=a[1]*b[2]-a[2]*b[1]; n=sqrt(d[v,1]^2+d[v,2]^2+d[v,3]^2); for(c=1;c<=3;c++) d[v,c]/=n} det=d[0,1]*(d[1,2]*d[2,3]-d[1,3]*d[2,2])-d[0,2]*(d[1,1]*d[2,3]-d[1,3]*d[2,1])+d[0,3]*(d[1,1]*d[2,2]-d[1,2]*d[2,1]); print \"det\", det; exit !(det<1e-12 && det>-1e-12)}' s/truth.cameras"
  STDOUT_MATCH "det ")
tpkit_tool_test(tp-synth.cross-track-default-has-no-key
  COMMAND "tp-synth --out s --size 160 --points 20 --supersample 1 >/dev/null 2>&1 && ! grep -q cross_track s/scene.params && echo none"
  STDOUT_MATCH "none")
tpkit_tool_test(tp-synth.cross-track-bad
  COMMAND "tp-synth --out s --size 64 --cross-track 1,2" EXPECT_FAIL STDERR_MATCH "one angle or three" NO_FILE s/scene.params)
# RPCs: each view's fitted RPC00B (tag 50844 and viewN_rpc.txt) within 0.01 px of its camera, truth.bias,
# truth.dem.tif; bad --origin / --rpc-bias refused.
tpkit_tool_test(tp-synth.rpc-files
  COMMAND "tp-synth --out out --size 256 --relief 20 --points 30 --origin -33.9,18.4,50 --rpc-bias 3:1.5,-2,0.001,0 && for f in view1_rpc.txt view2_rpc.txt view3_rpc.txt truth.bias truth.dem.tif @SEMI@ do test -s out/$f || echo MISSING $f @SEMI@ done && cmp <(grep -v '^#' out/truth.bias | tail -1) <(echo '3 1.5 0 0.001 -2 0 0') && echo same"
  STDOUT_MATCH "^same\n$"
  CHECK_FILE out/truth.tracks
  FILE_MATCH "# origin: -33.9,18.4,50 .*# rpc_fit_view1_px: rms [0-9.e-]+, max ([0-9]\\.[0-9]+e-[0-9]+|0\\.00[0-9]*)\n")
tpkit_tool_test(tp-synth.bad-origin
  COMMAND "tp-synth --out out --origin 43.3,5.4"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --origin: expected LAT,LON,H" NO_FILE out)
tpkit_tool_test(tp-synth.bad-rpc-bias
  COMMAND "tp-synth --out out --rpc-bias 4:1,2"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --rpc-bias: the view must be 1, 2 or 3" NO_FILE out)
# interrupted before it commits, a run leaves no folder it made (an empty scene folder stayed)
tpkit_tool_test(tp-synth.interrupted-leaves-no-folder
  COMMAND "(tp-synth --out new/scene --size 3000 --relief 10 --points 20 & pid=$! @SEMI@ sleep 2 @SEMI@ kill -TERM $pid @SEMI@ wait $pid @SEMI@ echo killed $?) && test ! -e new && echo nothing-left"
  STDOUT_MATCH "killed 143\nnothing-left")

# Blocks (--views N, --dates D): N views, truth tracks with nan for the views that do not see a point and
# 2 views or more each, no trifocal tensor; bad view counts and out-of-range --rpc-bias views refused.
tpkit_tool_test(tp-synth.block-truth
  COMMAND "tp-synth --out b --views 6 --dates 2 --size 128 --relief 10 --points 60 --supersample 1 --threads 2 2>/dev/null && ls b/view*.tif | wc -l && awk '/^# columns:/{print} !/^#/{n=0 @SEMI@ for(v=0 @SEMI@ v<6 @SEMI@ v++) if($(2+2*v)!=\"nan\") n++ @SEMI@ if(n<2) bad++ @SEMI@ if(n<6) part++ @SEMI@ rec++} END{print \"records\", rec, \"short\", bad+0, \"partial\", (part>0)}' b/truth.tracks"
  STDOUT_MATCH "^6\n# columns: track x1 y1 x2 y2 x3 y3 x4 y4 x5 y5 x6 y6 X Y Z lon lat h\nrecords 60 short 0 partial 1\n$"
  CHECK_FILE b/truth.tracks
  FILE_MATCH "# image6: view6.tif 128 128\n.*# block: 2 dates x 3 views.*# footprint_overlap: 1-2 0\\.[3-6][0-9], 1-4 .*# tracks_by_views: 2:"
  NO_FILE b/truth.trifocal)
# --random-bias: every view but view 1 and those of --rpc-bias (here 5, kept unbiased) gets a seeded bias
# of at most 10 px; the same seed gives the same truth.bias
tpkit_tool_test(tp-synth.block-random-bias
  COMMAND "tp-synth --out a --views 12 --size 96 --relief 5 --points 40 --supersample 1 --random-bias 10 --rpc-bias 5:0,0 2>/dev/null && tp-synth --out b --views 12 --size 96 --relief 5 --points 40 --supersample 1 --random-bias 10 --rpc-bias 5:0,0 2>/dev/null && cmp <(grep -v '^# written-by' a/truth.bias) <(grep -v '^# written-by' b/truth.bias) && awk '!/^#/{z=($2==0&&$3==0&&$4==0&&$5==0&&$6==0&&$7==0) @SEMI@ big=0 @SEMI@ for(x=0 @SEMI@ x<=95 @SEMI@ x+=95) for(y=0 @SEMI@ y<=95 @SEMI@ y+=95){dx=$2+$3*x+$4*y @SEMI@ dy=$5+$6*x+$7*y @SEMI@ if(dx*dx>100||dy*dy>100) big=1} printf \"%s%s \", $1, (z?\"=0\":(big?\"!\":\"b\"))} END{print \"\"}' a/truth.bias"
  STDOUT_MATCH "^1=0 2b 3b 4b 5=0 6b 7b 8b 9b 10b 11b 12b \n$")
tpkit_tool_test(tp-synth.block-views-not-multiple-of-dates
  COMMAND "tp-synth --out out --views 12 --dates 5"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --views 12 must be --dates \\(5\\) times 1 to 5 views per date" NO_FILE out)
tpkit_tool_test(tp-synth.block-views-need-dates
  COMMAND "tp-synth --out out --views 4"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --views 4 is not a multiple of 3.*give --dates" NO_FILE out)
tpkit_tool_test(tp-synth.block-too-many-views
  COMMAND "tp-synth --out out --views 200"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --views must be between 2 and 96" NO_FILE out)
tpkit_tool_test(tp-synth.block-rpc-bias-view-out-of-range
  COMMAND "tp-synth --out out --views 12 --rpc-bias 13:1,2"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --rpc-bias: the view must be between 1 and 12, got '13'" NO_FILE out)
tpkit_tool_test(tp-synth.block-bad-random-bias
  COMMAND "tp-synth --out out --views 12 --random-bias -1"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --random-bias must be between 0 and 1000" NO_FILE out)
# a triplet written over a block leaves none of the block's views 4..N behind
tpkit_tool_test(tp-synth.block-then-triplet-no-stale-views
  COMMAND "tp-synth --out s --views 6 --size 64 --relief 5 --points 10 --supersample 1 2>/dev/null && test -e s/view6.tif && tp-synth --out s --size 64 --relief 5 --points 10 --supersample 1 2>/dev/null && ls s | tr '\\n' ' '"
  STDOUT_MATCH "^scene.params truth.bias truth.cameras truth.dem.tif truth.tracks truth.trifocal view1.tif view1_rpc.txt view2.tif view2_rpc.txt view3.tif view3_rpc.txt $")
# Conditions (--second-date, --clouds, --water, --nodata-band) change the radiometry only: the truth
# tracks, cameras and RPCs are those of the same scene without them, and view 1 (the reference date,
# no water here) is the same image; scene.params records them and reloads.
tpkit_tool_test(tp-synth.conditions-keep-the-truth
  COMMAND "tp-synth --out a --size 128 --relief 5 --points 20 --threads 2 && tp-synth --out b --size 128 --relief 5 --points 20 --threads 2 --second-date 1 --clouds 0.3 --nodata-band 0.25 && for f in truth.tracks truth.cameras view2_rpc.txt @SEMI@ do cmp <(grep -v -e '^# written-by' -e '^# conditions' a/$f) <(grep -v -e '^# written-by' -e '^# conditions' b/$f) || exit 1 @SEMI@ done && cmp <(tail -c 20000 a/view1.tif) <(tail -c 20000 b/view1.tif) && ! cmp -s <(tail -c 20000 a/view2.tif) <(tail -c 20000 b/view2.tif) && grep -q '^# conditions: second_date 1 clouds 0.3 water 0 nodata_band 0.25' b/truth.tracks && grep -q '^clouds = 0.3$' b/scene.params && ! grep -q clouds a/scene.params && echo truth-kept"
  STDOUT_MATCH "truth-kept")
tpkit_tool_test(tp-synth.conditions-out-of-range
  COMMAND "tp-synth --out a --size 128 --clouds 0.9"
  EXPECT_FAIL STDERR_MATCH "--clouds must be a fraction between 0 and 0.8" NO_FILE a)
if(TPKIT_BENCH)
# A second date (half strength) with 20 % clouds, 10 % water and a 20 % nodata band: the pair view1-view2
# still gives >= 200 verified matches, and the triplets' error against the truth stays within
# 0.1 px median / 0.35 px p90 (measured 0.058..0.071 / 0.24..0.28).
tpkit_tool_test(tp-synth.conditions-still-matched
  COMMAND "tp-synth --out s --size 512 --seed 3 --relief 15 --second-date 0.5 --clouds 0.2 --water 0.1 --nodata-band 0.2 --threads 2 && bench_match_accuracy --synth s --threads 2 --nodata 0 --check 0.1 0.35"
  STDOUT_MATCH "pair view1-view2: keypoints [0-9]+/[0-9]+, verified [2-9][0-9][0-9]," TIMEOUT 120)
endif()
# Sensors of views 2..N (--blur, --resolution-ratio, --rotation). The truth check: every view's truth x y
# is the projection of the track's X Y Z through that view's truth.cameras matrix (within 1e-6 px), which
# with the RPC fit lines (max below 0.01 px, else tp-synth refuses) ties tracks, cameras and RPCs together.
set(_synth_truth "awk 'FNR == NR { if (/^# view /) { v++ @SEMI@ r = 0 } else if (!/^#/ && NF == 4) { for (c = 1 @SEMI@ c <= 4 @SEMI@ c++) P[v, r, c] = $c @SEMI@ r++ } next } /^#/ { next } { for (w = 1 @SEMI@ w <= v @SEMI@ w++) { if ($(2 * w) == \"nan\") continue @SEMI@ for (i = 0 @SEMI@ i < 3 @SEMI@ i++) h[i] = P[w, i, 1] * $(2 + 2 * v) + P[w, i, 2] * $(3 + 2 * v) + P[w, i, 3] * $(4 + 2 * v) + P[w, i, 4] @SEMI@ d = sqrt((h[0] / h[2] - $(2 * w)) ^ 2 + (h[1] / h[2] - $(2 * w + 1)) ^ 2) @SEMI@ if (d > e) e = d @SEMI@ n++ } } END { print \"truth\", n, \"projections, max error\", (e < 1e-6 ? \"below 1e-6 px\" : e) @SEMI@ exit !(n > 0 && e < 1e-6) }'")
set(_synth_rpc_fit "# rpc_fit_view1_px: rms [0-9.e-]+, max [0-9.e-]+\n# rpc_fit_view2_px: rms [0-9.e-]+, max ([0-9]\\.[0-9]+e-(0[3-9]|[1-9][0-9])|0\\.00[0-9]*)\n")
# --blur: radiometric only, as the conditions: truth, cameras and RPCs are those of the scene without it,
# view 1 the same image, view 2 not; scene.params records it.
tpkit_tool_test(tp-synth.blur-keeps-the-truth
  COMMAND "tp-synth --out a --size 128 --relief 5 --points 20 --supersample 1 --threads 2 >/dev/null 2>&1 && tp-synth --out b --size 128 --relief 5 --points 20 --supersample 1 --threads 2 --blur 1.5 >/dev/null 2>&1 && for f in truth.tracks truth.cameras view2_rpc.txt @SEMI@ do cmp <(grep -v '^# written-by' a/$f) <(grep -v '^# written-by' b/$f) || exit 1 @SEMI@ done && cmp <(tail -c 20000 a/view1.tif) <(tail -c 20000 b/view1.tif) && ! cmp -s <(tail -c 20000 a/view2.tif) <(tail -c 20000 b/view2.tif) && grep -q '^blur = 1.5$' b/scene.params && ! grep -q blur a/scene.params && echo truth-kept"
  STDOUT_MATCH "^truth-kept\n$")
# --resolution-ratio 2: views 2 and 3 have half the image scale of the same scene without it (the norm of
# their cameras' first row), view 1 the same; the truth follows the cameras and the RPCs fit them.
tpkit_tool_test(tp-synth.resolution-ratio-truth
  COMMAND "tp-synth --out a --size 128 --relief 10 --points 30 --supersample 1 --threads 2 >/dev/null 2>&1 && tp-synth --out b --size 128 --relief 10 --points 30 --supersample 1 --threads 2 --resolution-ratio 2 >/dev/null 2>&1 && grep -q '^resolution_ratio = 2$' b/scene.params && ${_synth_truth} b/truth.cameras b/truth.tracks && awk '!/^#/ && NF == 4 && ++k % 3 == 1 { s[k] = sqrt($1 ^ 2 + $2 ^ 2 + $3 ^ 2) } END { for (a = 1 @SEMI@ a <= 7 @SEMI@ a += 3) printf \"scale %.9f\\n\", s[a + 9] / s[a] }' a/truth.cameras b/truth.cameras"
  STDOUT_MATCH "^truth 90 projections, max error below 1e-6 px\nscale 1\\.000000000\nscale 0\\.500000000\nscale 0\\.500000000\n$"
  CHECK_FILE b/truth.tracks
  FILE_MATCH "${_synth_rpc_fit}")
# --rotation 30: views 2 and 3's image x axis is turned by 30 deg about the optical axis from where it was
# without it (the angle between their cameras' first rows, s times the x axis), view 1's unchanged; with
# --resolution-ratio 3, --blur 1 and conditions, the truth still follows the cameras.
tpkit_tool_test(tp-synth.rotation-truth
  COMMAND "tp-synth --out a --size 128 --relief 10 --points 30 --supersample 1 --threads 2 >/dev/null 2>&1 && tp-synth --out b --size 128 --relief 10 --points 30 --supersample 1 --threads 2 --rotation 30 --resolution-ratio 3 --blur 1 --second-date 0.5 --clouds 0.2 >/dev/null 2>&1 && grep -q '^rotation = 30$' b/scene.params && ${_synth_truth} b/truth.cameras b/truth.tracks && awk '!/^#/ && NF == 4 && ++k % 3 == 1 { for (c = 1 @SEMI@ c <= 3 @SEMI@ c++) r[k, c] = $c } END { for (v = 0 @SEMI@ v < 3 @SEMI@ v++) { a = 3 * v + 1 @SEMI@ b = a + 9 @SEMI@ d = 0 @SEMI@ na = 0 @SEMI@ nb = 0 @SEMI@ for (c = 1 @SEMI@ c <= 3 @SEMI@ c++) { d += r[a, c] * r[b, c] @SEMI@ na += r[a, c] ^ 2 @SEMI@ nb += r[b, c] ^ 2 } x = d / sqrt(na * nb) @SEMI@ printf \"turned %.6f\\n\", atan2(sqrt(1 - x * x), x) * 45 / atan2(1, 1) } }' a/truth.cameras b/truth.cameras"
  STDOUT_MATCH "^truth 90 projections, max error below 1e-6 px\nturned 0\\.0000[0-9]+\nturned (29\\.99999[0-9]|30\\.00000[0-9])\nturned (29\\.99999[0-9]|30\\.00000[0-9])\n$"
  CHECK_FILE b/truth.tracks
  FILE_MATCH "${_synth_rpc_fit}")
tpkit_tool_test(tp-synth.blur-out-of-range
  COMMAND "tp-synth --out a --size 64 --blur 6" EXPECT_FAIL STDERR_MATCH "^tp-synth: --blur must be between 0 and 5 pixels, got 6\n$" NO_FILE a)
tpkit_tool_test(tp-synth.resolution-ratio-out-of-range
  COMMAND "tp-synth --out a --size 64 --resolution-ratio 0.5"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --resolution-ratio must be between 1 and 4, got 0\\.5\n$" NO_FILE a)
tpkit_tool_test(tp-synth.rotation-out-of-range
  COMMAND "tp-synth --out a --size 64 --rotation 200"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --rotation must be between -180 and 180 degrees, got 200\n$" NO_FILE a)
if(TPKIT_BENCH)
# The pixels follow the geometric families' truth: view 2 at twice the GSD and turned by 30 deg, matched by
# tp-match and scored against the truth projection through view 2's camera: >= 500 correct matches, median
# error below 0.1 px (measured 1060 of 1066, median 0.037 px).
tpkit_tool_test(tp-synth.sensor-pixels-follow-the-truth
  COMMAND "tp-synth --out s --size 512 --seed 3 --relief 15 --resolution-ratio 2 --rotation 30 --threads 2 >/dev/null 2>&1 && tp-match s/view1.tif s/view2.tif --threads 2 -q -o m.matches && bench_match_accuracy --synth s --score m.matches 1 2"
  STDOUT_MATCH "correct \\(< 1 px\\) ([5-9][0-9][0-9]|[0-9][0-9][0-9][0-9]+), correct median 0\\.0[0-9]* " TIMEOUT 120)
endif()

# --scene buildings: the truth goes through buildings and trees. Every seen position is the projection of its
# ground point through truth.cameras; a block's truth marks points hidden by walls and crowns (nan although
# the point projects inside the image: none without structures, as tp-synth.block-truth's scene); ground
# points reach roofs above the 10 m relief; scene.params records the structures, and the run says how many.
tpkit_tool_test(tp-synth.buildings-truth
  COMMAND "tp-synth --out b --scene buildings --views 6 --dates 2 --size 160 --relief 10 --points 200 --supersample 1 --threads 2 && grep -c '^buildings = 0.45$\\|^trees = 0.35$' b/scene.params && awk -v size=160 -f $SRC/tests/tools/synth_truth_check.awk b/truth.cameras b/truth.tracks && tp-synth --out a --views 6 --dates 2 --size 160 --relief 10 --points 200 --supersample 1 --threads 2 2>/dev/null && awk -v size=160 -f $SRC/tests/tools/synth_truth_check.awk a/truth.cameras a/truth.tracks"
  STDERR_MATCH "[0-9]+ buildings, [0-9]+ trees"
  STDOUT_MATCH "^2\nseen [0-9]+ max error ok hidden [1-9][0-9]* high 1\nseen [0-9]+ max error ok hidden 0 high 0\n$")
tpkit_tool_test(tp-synth.buildings-triplet
  COMMAND "tp-synth --out t --scene buildings --buildings 0.7 --size 192 --relief 10 --points 150 --supersample 1 --threads 2 2>/dev/null && grep -c '^buildings = 0.7$\\|^trees = 0.35$' t/scene.params && awk -v size=192 -f $SRC/tests/tools/synth_truth_check.awk t/truth.cameras t/truth.tracks"
  STDOUT_MATCH "^2\nseen 450 max error ok hidden 0 high 1\n$")
tpkit_tool_test(tp-synth.bad-scene
  COMMAND "tp-synth --out out --scene castle"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --scene must be default or buildings, got 'castle'" NO_FILE out)
tpkit_tool_test(tp-synth.bad-buildings
  COMMAND "tp-synth --out out --buildings 2"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --buildings must be a fraction between 0 and 1" NO_FILE out)
