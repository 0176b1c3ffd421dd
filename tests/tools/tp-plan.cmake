# tp-plan: the files it writes (quoting of names with spaces and quotes, stages, Makefile), bad input,
# and the plan run for real by make, GNU parallel and a single-node Slurm started by the test
# (scale_out_engine.sh: fails, never skips, when slurm-wlm, munge or parallel is missing).
set(_imgs "tp-synth --out s --size 300 --seed 2 --threads 2 --supersample 1 >/dev/null && mkdir -p 'my imgs' && cp s/view1.tif \"my imgs/it's 1.tif\" && cp s/view2.tif 'my imgs/$x 2.tif'")
tpkit_tool_test(tp-plan.files
  COMMAND "${_imgs} && tp-plan -q -o 'w d' --tile 256 \"my imgs/it's 1.tif\" 'my imgs/$x 2.tif' && cat 'w d/jobs/tiles.jobs' 'w d/plan.mk' 'w d/jobs/chain.jobs' && bash -n 'w d/submit-slurm.sh' && bash -n 'w d/run-parallel.sh' && bash -n 'w d/slurm-array.sbatch'"
  STDOUT_MATCH "^tp-match -q --threads 1 --tile 768 --geometry '[^']*/w d/geometry/pair-1-2.geometry' --region 0 0 256 256 --cache '[^']*/w d/cache' -o '[^']*/w d/tiles/pair-1-2/tile-1.matches' '[^']*/my imgs/it'\\\\''s 1.tif' '[^']*/my imgs/[$]x 2.tif'\n.*--region 256 256 44 44 .*tile-4.matches.*\ntpkit-all: ground.points\n.*detect/image-2/block-1.detection: geometry/pair-1-2.geometry\n\t[^\n]*--detect 2 --region 0 0 300 256 [^\n]*\n.*tiles/pair-1-2/tile-1.matches: geometry/pair-1-2.geometry [$][(]detect-image-1[)] [$][(]detect-image-2[)]\n\t.*'[^']*/my imgs/[$][$]x 2.tif'\n.*tracks.tracks: pairs/pair-1-2.matches\n\ttp-chain -q --rpc-check 1 --threads 1 --unrefined --images [^\n]*\nrefined.tracks: tracks.tracks\n\ttp-refine -q [^\n]* --tracks '[^']*/w d/tracks.tracks' --threads 1 -o '[^']*/w d/refined.tracks'\nadjusted/rpc.bias: refined.tracks\n\trpc-adjust '[^']*/my imgs/it'\\\\''s 1.tif' '[^']*/my imgs/[$][$]x 2.tif' --tracks ")
tpkit_tool_test(tp-plan.make-dry-run
  COMMAND "${_imgs} && tp-plan -q -o w --tile 256 --overlap 16 --threads 2 s/view1.tif s/view2.tif s/view3.tif && make -n -C w -f plan.mk > n && grep -c '^tp-match .*--region' n && grep -c '^tp-match .*--detect' n"
  STDOUT_MATCH "^15\n3\n$")
# detection jobs: blocks of up to --detect-regions regions of a row; a 600² pair, regions and detection
# tiles of 256 px (2 x 2 detection tiles an image): one job per tile with 1, one per row of tiles with 2
tpkit_tool_test(tp-plan.detect-regions
  COMMAND "tp-synth --out s --size 600 --seed 2 --threads 2 --supersample 1 >/dev/null && for r in 1 2; do tp-plan -q -o w$r --tile 256 --detect-tile 256 --detect-regions $r s/view1.tif s/view2.tif && wc -l < w$r/jobs/detect.jobs && grep -o -- '--detect 2 --region [0-9 ]*' w$r/jobs/detect.jobs; done"
  STDOUT_MATCH "^8\n--detect 2 --region 0 0 256 256 \n--detect 2 --region 256 0 256 256 \n--detect 2 --region 0 256 256 256 \n--detect 2 --region 256 256 256 256 \n4\n--detect 2 --region 0 0 512 256 \n--detect 2 --region 0 256 512 256 \n$")
tpkit_tool_test(tp-plan.detect-regions-zero
  COMMAND "tp-synth --out s --size 300 --seed 2 --threads 2 --supersample 1 >/dev/null && tp-plan -o w --detect-regions 0 s/view1.tif s/view2.tif" EXPECT_FAIL STDERR_MATCH "\ntp-plan: --detect-regions: " NO_FILE w)
tpkit_tool_test(tp-plan.list
  COMMAND "${_imgs} && printf '# views\\n%s\\n\\n%s\\n' \"$PWD/my imgs/it's 1.tif\" s/view2.tif > list && tp-plan -o w --list list"
  STDERR_MATCH "2 images, 1 pairs, 2 detection jobs, 1 region jobs")
tpkit_tool_test(tp-plan.tile-in-match-options
  COMMAND "${_imgs} && tp-plan -o w --match-options '--tile 512' s/view1.tif s/view2.tif" EXPECT_FAIL STDERR_MATCH "--detect-tile" NO_FILE w)
# pairs from the RPC footprints (tp-synth writes a model beside each view): a view of a scene 1 degree
# north overlaps none of the others and is left out, of the pairs and of the chain
tpkit_tool_test(tp-plan.rpc-footprints
  COMMAND "${_imgs} && tp-synth --out far --size 256 --seed 3 --threads 2 --supersample 1 --origin 44.3,5.4,100 >/dev/null && tp-plan -o w s/view1.tif s/view2.tif s/view3.tif far/view1.tif && cat w/jobs/geometry.jobs | wc -l && (grep -c far w/jobs/chain.jobs || true)"
  STDOUT_MATCH "^3\n0\n$"
  STDERR_MATCH "far/view1.tif: its RPC footprint meets no other image's: left out of the plan\n.*4 images, 3 pairs")
tpkit_tool_test(tp-plan.one-image
  COMMAND "${_imgs} && tp-plan -o w s/view1.tif" EXPECT_FAIL STDERR_MATCH "two images or more" NO_FILE w)
tpkit_tool_test(tp-plan.unreadable-image
  COMMAND "${_imgs} && tp-plan -o w s/view1.tif missing.tif" EXPECT_FAIL STDERR_MATCH "missing.tif" NO_FILE w)
tpkit_tool_test(tp-plan.twice
  COMMAND "${_imgs} && tp-plan -o w s/view1.tif ./s/view1.tif" EXPECT_FAIL STDERR_MATCH "listed twice" NO_FILE w)
tpkit_tool_test(tp-plan.line-break
  COMMAND "${_imgs} && cp s/view1.tif \"$(printf 'a\\nb.tif')\" && tp-plan -o w s/view1.tif a?b.tif" EXPECT_FAIL STDERR_MATCH "line break" NO_FILE w)
foreach(engine slurm parallel make)
  tpkit_tool_test(tp-plan.engine-${engine}
    COMMAND "bash \"$SRC/tests/tools/scale_out_engine.sh\" ${engine} \"$(dirname \"$(command -v tp-plan)\")\""
    STDOUT_MATCH "PASS: ${engine}" TIMEOUT 300 LABELS engine ${engine} slow)
endforeach()
# issue 23: a work folder is never reused for another plan (images in another order made make say
# "Nothing to be done" while the old outputs stood for other pairs), nor one holding outputs without a
# plan; the same plan again resumes. A model path that is a device is refused before any read.
# run-parallel.sh being a folder fails before the success summary and leaves no folder made.
# plan.mk grows with the pairs, not with pairs x images (each region rule named every detection report).
tpkit_tool_test(tp-plan.reused-folder-other-order
  COMMAND "${_imgs} && tp-plan -q -o w s/view1.tif s/view2.tif s/view3.tif && tp-plan -q -o w s/view1.tif s/view2.tif s/view3.tif && echo same-plan-ok && cp w/plan.mk before && tp-plan -q -o w s/view2.tif s/view1.tif s/view3.tif @SEMI@ echo exit $? && cmp before w/plan.mk && echo untouched"
  STDOUT_MATCH "same-plan-ok\nexit 2\nuntouched" STDERR_MATCH "w: holds another plan \\(its plan.mk differs: other images, another order")
tpkit_tool_test(tp-plan.outputs-without-plan
  COMMAND "${_imgs} && mkdir -p w/pairs && touch w/pairs/pair-1-2.matches && tp-plan -q -o w s/view1.tif s/view2.tif"
  EXPECT_FAIL STDERR_MATCH "w: holds outputs of a plan \\(pairs\\) but no plan.mk" NO_FILE w/plan.mk)
tpkit_tool_test(tp-plan.list-is-a-device
  COMMAND "${_imgs} && timeout 20 tp-plan -o w --list /dev/zero"
  EXPECT_FAIL STDERR_MATCH "tp-plan: /dev/zero: not a regular file or a pipe" NO_FILE w)
tpkit_tool_test(tp-plan.runner-name-is-a-folder
  COMMAND "${_imgs} && mkdir -p w/run-parallel.sh && (tp-plan -o w s/view1.tif s/view2.tif 2> err @SEMI@ echo exit $?) && cat err && ls w && (grep -c 'region jobs' err || true)"
  STDOUT_MATCH "^exit 1\ntp-plan: [^\n]*w/run-parallel.sh: cannot write: is a folder\nrun-parallel.sh\n0\n$")
tpkit_tool_test(tp-plan.size-grows-with-pairs
  COMMAND "${_imgs} && mkdir many && for i in $(seq 40) @SEMI@ do cp s/view1.tif many/v$i.tif @SEMI@ cp s/view1_rpc.txt many/v$i\\_rpc.txt @SEMI@ done && tp-plan -q -o w many/v*.tif && pairs=$(wc -l < w/jobs/geometry.jobs) && bytes=$(wc -c < w/plan.mk) && echo \"$pairs pairs, $((bytes / pairs)) bytes per pair\" && test $bytes -lt $((pairs * 1500))"
  STDOUT_MATCH "^780 pairs, [0-9]+ bytes per pair\n$")
# issue 24: the plan ends in the adjustment. After the chain, rpc-adjust (the chain's images, its tracks,
# the options given) into WORK/adjusted, then tp-ground through the adjusted models into
# WORK/ground.points; make runs them in that order, last. An image without a model ends the plan at the
# chain (warned), or refuses it when the adjustment is asked for; the options tp-plan sets are refused in
# --adjust-options / --ground-options; --no-adjust ends at the chain.
tpkit_tool_test(tp-plan.adjust-stages
  COMMAND "${_imgs} && tp-plan -q -o w --fixed s/view1.tif --adjust-model shift --adjust-options '--loss 0.5 --dem s/truth.dem.tif' --ground-options '--crs utm' s/view1.tif \"my imgs/it's 1.tif\" s/view3.tif && cat w/jobs/adjust.jobs w/jobs/ground.jobs && grep '^tpkit-all' w/plan.mk && grep -A1 -e '^adjusted/rpc.bias:' -e '^ground.points:' w/plan.mk | grep -v '^\t' && make -n -C w -f plan.mk | grep -o -e '^tp-[a-z]*' -e '^rpc-adjust' | uniq | tail -3 && tail -3 w/submit-slurm.sh && grep '^for s' w/run-parallel.sh"
  STDOUT_MATCH "^rpc-adjust '[^']*/s/view1.tif' '[^']*/my imgs/it'\\\\''s 1.tif' '[^']*/s/view3.tif' --tracks '[^']*/w/refined.tracks' --model shift --fixed '[^']*/s/view1.tif' --threads 1 '--loss' '0.5' '--dem' '/[^']*/s/truth.dem.tif' -o '[^']*/w/adjusted'\ntp-ground '[^']*/s/view1.tif' '[^']*/my imgs/it'\\\\''s 1.tif' '[^']*/s/view3.tif' --tracks '[^']*/w/refined.tracks' --rpc '[^']*/s/view1.tif=[^']*/w/adjusted/view1_rpc.txt' --rpc '[^']*/my imgs/it'\\\\''s 1.tif=[^']*/w/adjusted/it'\\\\''s 1_rpc.txt' --rpc '[^']*/s/view3.tif=[^']*/w/adjusted/view3_rpc.txt' --threads 1 '--crs' 'utm' -o '[^']*/w/ground.points'\ntpkit-all: ground.points\nadjusted/rpc.bias: refined.tracks\nground.points: adjusted/rpc.bias refined.tracks\ntp-refine\nrpc-adjust\ntp-ground\nsubmit refine 1\nsubmit adjust 1\nsubmit ground 1 \"[$][{]wait\\[@\\][}]\"\nfor s in geometry detect tiles merge chain refine adjust ground@SEMI@ do\n$")
tpkit_tool_test(tp-plan.image-without-model
  COMMAND "${_imgs} && oiiotool s/view1.tif -o plain.tif && tp-plan -o w s/view2.tif plain.tif 2> err && ls w/jobs && grep '^tpkit-all' w/plan.mk && cat err"
  STDOUT_MATCH "^chain.jobs\ndetect.jobs\ngeometry.jobs\nmerge.jobs\ntiles.jobs\ntpkit-all: tracks.tracks\ntp-plan: warning: [^\n]*/plain.tif: no RPC model [^\n]*: the adjustment needs one for every image@SEMI@ the plan ends with the chain [(]tracks.tracks[)], without the adjust and ground stages\ntp-plan: 2 images, 1 pairs, [^\n]*, ending with the chain in tracks.tracks@SEMI@ ")
tpkit_tool_test(tp-plan.image-without-model-adjust
  COMMAND "${_imgs} && oiiotool s/view1.tif -o plain.tif && tp-plan -o w --adjust s/view2.tif plain.tif"
  EXPECT_FAIL STDERR_MATCH "\ntp-plan: [^\n]*/plain.tif: no RPC model [^\n]*: the adjustment needs one for every image\n$" NO_FILE w)
tpkit_tool_test(tp-plan.image-without-model-fixed
  COMMAND "${_imgs} && oiiotool s/view1.tif -o plain.tif && tp-plan -o w --fixed s/view2.tif s/view2.tif plain.tif"
  EXPECT_FAIL STDERR_MATCH "plain.tif: no RPC model" NO_FILE w)
tpkit_tool_test(tp-plan.same-name-twice
  COMMAND "${_imgs} && mkdir b && cp s/view1.tif b/view1.tif && tp-plan -o w --adjust s/view1.tif b/view1.tif"
  EXPECT_FAIL STDERR_MATCH "b/view1.tif: another image of the plan is also named view1.[*]: rpc-adjust names the adjusted models by it" NO_FILE w)
tpkit_tool_test(tp-plan.no-adjust
  COMMAND "${_imgs} && tp-plan -q -o w --no-adjust s/view1.tif s/view2.tif && ls w/jobs && grep '^tpkit-all' w/plan.mk"
  STDOUT_MATCH "^chain.jobs\ndetect.jobs\ngeometry.jobs\nmerge.jobs\ntiles.jobs\ntpkit-all: tracks.tracks\n$")
tpkit_tool_test(tp-plan.no-adjust-with-fixed
  COMMAND "${_imgs} && tp-plan -o w --no-adjust --fixed s/view1.tif s/view1.tif s/view2.tif"
  EXPECT_FAIL STDERR_MATCH "--no-adjust excludes" NO_FILE w)
tpkit_tool_test(tp-plan.fixed-not-an-image
  COMMAND "${_imgs} && tp-plan -o w --fixed s/view3.tif s/view1.tif s/view2.tif"
  EXPECT_FAIL STDERR_MATCH "\ntp-plan: --fixed [^\n]*/s/view3.tif: not one of the plan's images\n$" NO_FILE w)
tpkit_tool_test(tp-plan.adjust-options-model
  COMMAND "${_imgs} && tp-plan -o w --adjust-options '--loss 2 --model shift' s/view1.tif s/view2.tif"
  EXPECT_FAIL STDERR_MATCH "\ntp-plan: --adjust-options: --model is refused there: it is tp-plan's --adjust-model\n$" NO_FILE w)
tpkit_tool_test(tp-plan.ground-options-rpc
  COMMAND "${_imgs} && tp-plan -o w --ground-options '--rpc a=b' s/view1.tif s/view2.tif"
  EXPECT_FAIL STDERR_MATCH "\ntp-plan: --ground-options: --rpc is refused there" NO_FILE w)
tpkit_tool_test(tp-plan.adjust-model-unknown
  COMMAND "${_imgs} && tp-plan -o w --adjust-model projective s/view1.tif s/view2.tif"
  EXPECT_FAIL STDERR_MATCH "\ntp-plan: --adjust-model projective: expected shift, drift or affine\n$" NO_FILE w)
tpkit_tool_test(tp-plan.adjusted-without-plan
  COMMAND "${_imgs} && mkdir -p w/adjusted && touch w/adjusted/rpc.bias && tp-plan -q -o w s/view1.tif s/view2.tif"
  EXPECT_FAIL STDERR_MATCH "w: holds outputs of a plan \\(adjusted\\) but no plan.mk" NO_FILE w/plan.mk)
# --ortho-options: the ortho stage after the adjustment, one tp-ortho job through the adjusted models
# (the DEM's name made absolute), among make's final targets; run for real by make, its orthos on one
# grid; --ortho-options without the heights is refused.
tpkit_tool_test(tp-plan.ortho-stage
  COMMAND "tp-synth --out s --size 300 --seed 2 --threads 2 --supersample 1 >/dev/null && tp-plan -q -o w --fixed s/view1.tif --ortho-options '--dem s/truth.dem.tif --gsd 2' s/view1.tif s/view2.tif && cat w/jobs/ortho.jobs && grep '^tpkit-all' w/plan.mk && grep '^for s' w/run-parallel.sh && make -s -C w -f plan.mk -j2 >/dev/null 2>&1 && ls w/orthos && tp-ortho -q --compare w/orthos/view1.ortho.tif w/orthos/view2.ortho.tif | grep -vc '^#'"
  STDOUT_MATCH "^tp-ortho -q '[^']*/s/view1.tif' '[^']*/s/view2.tif' --rpc '[^']*/s/view1.tif=[^']*/w/adjusted/view1_rpc.txt' --rpc '[^']*/s/view2.tif=[^']*/w/adjusted/view2_rpc.txt' --threads 1 '--dem' '/[^']*/s/truth.dem.tif' '--gsd' '2' -o '[^']*/w/orthos'\ntpkit-all: ground.points orthos/view1.ortho.tif\nfor s in geometry detect tiles merge chain refine adjust ground ortho@SEMI@ do\nview1.ortho.tif\nview2.ortho.tif\n1\n$")
tpkit_tool_test(tp-plan.ortho-options-need-heights
  COMMAND "tp-synth --out s --size 300 --seed 2 --threads 2 --supersample 1 >/dev/null && tp-plan -o w --ortho-options '--gsd 2' s/view1.tif s/view2.tif"
  EXPECT_FAIL STDERR_MATCH "\ntp-plan: --ortho-options: give the orthos' heights, --dem FILE or --height H\n$" NO_FILE w)
