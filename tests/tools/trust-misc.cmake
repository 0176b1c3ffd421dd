# Trust campaign (issue 50), group "misc": output commits, option helpers, tp-chain / tp-plan / tp-synth /
# tp-sample checks, and how --rpc IMAGE=FILE and --fixed name an image.
set(misc_synth "tp-synth -o syn --size 192 --relief 20 --points 100 --supersample 1 > /dev/null")
set(misc_ground3 "tp-ground syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks")
# what a case left in its folder beside syn/ and err (nothing after a failure)
set(misc_left "echo \"rc $? left $(ls | grep -v -e '^syn$' -e '^err$' | tr '\\n' ' ')\"")

# Item 6: a run writes all its files or none. /dev/full fails only when written: it is written before the
# files are put in place, so --dz and the --models folder (made by the run) are gone; and item 17: no
# "N ground points" summary before the write error.
tpkit_tool_test(trust-misc.ground-device-output-fails-whole-run
  COMMAND "${misc_synth} && ${misc_ground3} --align syn/truth.dem.tif --models newmod --dz dz.txt -o /dev/full 2> err @SEMI@ ${misc_left} @SEMI@ echo \"summaries $(grep -c 'ground points' err)\" @SEMI@ cat err >&2"
  STDOUT_MATCH "^rc 1 left \nsummaries 0\n$"
  STDERR_MATCH "tp-ground: /dev/full: write error")
# Item 6: --align on a DEM it cannot use fails after the --models folder was made: the folder goes too.
tpkit_tool_test(trust-misc.ground-failed-align-removes-models-folder
  COMMAND "${misc_synth} && ${misc_ground3} --align syn/view1.tif --models newmod/sub --dz dz.txt -o g.points 2> err @SEMI@ ${misc_left} @SEMI@ cat err >&2"
  STDOUT_MATCH "^rc 1 left \n$"
  STDERR_MATCH "tp-ground: syn/view1.tif: no georeferencing")
# Item 6: tp-match's --coverage on a full device: the matches file is not written either.
tpkit_tool_test(trust-misc.match-coverage-device-fails-whole-run
  COMMAND "tp-synth -o syn --size 128 --seed 1 > /dev/null && tp-match syn/view1.tif syn/view2.tif --coverage /dev/full -o p.matches"
  EXPECT_FAIL STDERR_MATCH "tp-match: /dev/full: write error" NO_FILE p.matches)
# Item 15: --rpc and --fixed name an image as a tracks file's image lines do: ./syn/view2.tif is
# syn/view2.tif. The wrong model given so (view3's) is used, and fails the fit; the right one passes.
tpkit_tool_test(trust-misc.rpc-other-spelling
  COMMAND "${misc_synth} && ${misc_ground3} --rpc ./syn/view2.tif=syn/view3_rpc.txt -o bad.points @SEMI@ echo rc $? @SEMI@ ${misc_ground3} --rpc ./syn/view2.tif=syn/view2_rpc.txt -o g.points && echo ok"
  STDOUT_MATCH "^rc 1\nok\n$"
  STDERR_MATCH "tracks have an RMS residual above --flag 2 px")
tpkit_tool_test(trust-misc.rpc-two-names-of-one-image
  COMMAND "${misc_synth} && ${misc_ground3} --rpc ./syn/view2.tif=syn/view2_rpc.txt --rpc syn/view2.tif=syn/view2_rpc.txt -o g.points"
  EXPECT_FAIL STDERR_MATCH "\ntp-ground: --rpc syn/view2.tif=syn/view2_rpc.txt: syn/view2.tif has another --rpc already\n$" NO_FILE g.points)
tpkit_tool_test(trust-misc.fixed-other-spelling
  COMMAND "${misc_synth} && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks --fixed ./syn/view1.tif -o adj"
  STDERR_MATCH "rpc-adjust: image1 syn/view1.tif \\(fixed\\)")
tpkit_tool_test(trust-misc.plan-fixed-through-a-link
  COMMAND "tp-synth --out s --size 300 --seed 2 --threads 2 --supersample 1 > /dev/null && ln -s s/view1.tif link.tif && tp-plan -q -o w --fixed link.tif s/view1.tif s/view2.tif && grep -o -- \"--fixed '[^']*'\" w/jobs/adjust.jobs"
  STDOUT_MATCH "^--fixed '/[^']*/s/view1.tif'\n$")

# Item 11: a matches file's sigma -1 is refused with its line (it became 0.7071 px in the tracks).
tpkit_tool_test(trust-misc.chain-negative-sigma
  COMMAND "printf '# tpkit matches 1\\n# image1: a.tif 100 100\\n# image2: b.tif 100 100\\n# columns: id1 x1 y1 id2 x2 y2 sigma\\n1 10 10 1 11 11 0.5\\n2 20 20 2 21 21 -1\\n' > m.matches && tp-chain m.matches -o t.tracks"
  EXPECT_FAIL STDERR_MATCH "^tp-chain: m.matches:6: sigma -1 is not a standard deviation \\(pixels, >= 0\\)\n$" NO_FILE t.tracks)
# Item 11: the file options of --adjust-options and --ground-options are made absolute (the jobs run in
# the work folder): --gcp, --align, --dz, --models as --dem and --check were.
tpkit_tool_test(trust-misc.plan-file-options-absolute
  COMMAND "tp-synth --out s --size 300 --seed 2 --threads 2 --supersample 1 > /dev/null && tp-plan -q -o w --adjust-options '--gcp g.gcp' --ground-options '--align s/truth.dem.tif --dz dz.txt --models m' s/view1.tif s/view2.tif && grep -o \"'--[a-z]*' '[^']*'\" w/jobs/adjust.jobs w/jobs/ground.jobs"
  STDOUT_MATCH "adjust.jobs:'--gcp' '/[^']*/g.gcp'\n.*ground.jobs:'--align' '/[^']*/s/truth.dem.tif'\n.*ground.jobs:'--dz' '/[^']*/dz.txt'\n.*ground.jobs:'--models' '/[^']*/m'\n")
# Item 11: --dates 0 is not a number of acquisitions (0 stood for the default inside).
tpkit_tool_test(trust-misc.synth-dates-zero
  COMMAND "tp-synth -o s --views 6 --dates 0 --size 64"
  EXPECT_FAIL STDERR_MATCH "^tp-synth: --dates: must be > 0, got '0'" NO_FILE s)
# Item 11: tp-sample reads a version-2 tracks file (a block's, views not seen "nan nan") as every
# tracks reader does, and writes it as version 2.
tpkit_tool_test(trust-misc.sample-tracks-version-2
  COMMAND "printf '# tpkit tracks 2\\n# image1: a.tif 100 100\\n# image2: b.tif 100 100\\n# image3: c.tif 100 100\\n# columns: track x1 y1 x2 y2 x3 y3\\n1 1 1 2 2 nan nan\\n2 3 3 4 4 5 5\\n3 6 6 nan nan 7 7\\n' > t.tracks && tp-sample t.tracks -n 2 --seed 3 -o s.tracks && tp-sample --kind tracks t.tracks -n 2 --seed 3 -o k.tracks && cmp s.tracks k.tracks && grep -c nan s.tracks"
  STDOUT_MATCH "^[12]\n$"
  CHECK_FILE s.tracks FILE_MATCH "^# tpkit tracks 2\n")

# Item 17: a UTF-8 byte order mark at the start of a --list file is not part of the first path.
tpkit_tool_test(trust-misc.plan-list-bom
  COMMAND "tp-synth --out s --size 300 --seed 2 --threads 2 --supersample 1 > /dev/null && printf '\\xef\\xbb\\xbfs/view1.tif\\r\\ns/view2.tif\\r\\n' > list && tp-plan -o w --list list"
  STDERR_MATCH "tp-plan: 2 images, 1 pairs")
# Item 17: an option of a fixed count given one value short takes the next argument and names itself
# in the error (it was the images' count: "IMAGES: At least 2 required but received 1").
tpkit_tool_test(trust-misc.match-region-one-number-short
  COMMAND "tp-match --region 0 0 100 a.tif b.tif -o r.matches"
  EXPECT_FAIL STDERR_MATCH "^tp-match: --region: X0 Y0 W H are whole pixels, got 'a.tif' \\(see tp-match --help\\)\n$" NO_FILE r.matches)
tpkit_tool_test(trust-misc.match-height-range-one-number-short
  COMMAND "tp-match --height-range 0 a.tif b.tif -o r.matches"
  EXPECT_FAIL STDERR_MATCH "^tp-match: [^\n]*--height-range[^\n]*a.tif" NO_FILE r.matches)
# Item 17: OpenCV's TBB pool is not asked for more workers than the processors (--threads 64 printed an
# unprefixed "TBB Warning: The number of workers is currently limited to ...").
tpkit_tool_test(trust-misc.match-threads-above-cores-no-tbb-warning
  COMMAND "tp-synth -o syn --size 128 --seed 1 > /dev/null && tp-match syn/view1.tif syn/view2.tif --threads 64 -q -o m.matches 2> err @SEMI@ echo \"rc $? tbb $(grep -c TBB err)\""
  STDOUT_MATCH "^rc 0 tbb 0\n$")
# Item 17: -o after --images is the output option (already right: CLI11 ends a list at an option); the
# MATCHES files after --images are taken as images, and the error now says so.
tpkit_tool_test(trust-misc.chain-output-after-images
  COMMAND "printf '# tpkit matches 1\\n# image1: a.tif 100 100\\n# image2: b.tif 100 100\\n# columns: id1 x1 y1 id2 x2 y2\\n1 10 10 1 11 11\\n' > m.matches && tp-chain m.matches --images a.tif b.tif -o t.tracks"
  CHECK_FILE t.tracks FILE_MATCH "^# tpkit tracks 1\n")
tpkit_tool_test(trust-misc.chain-matches-after-images
  COMMAND "printf '# tpkit matches 1\\n# image1: a.tif 100 100\\n# image2: b.tif 100 100\\n# columns: id1 x1 y1 id2 x2 y2\\n1 10 10 1 11 11\\n' > m.matches && tp-chain --images a.tif b.tif m.matches -o t.tracks"
  EXPECT_FAIL STDERR_MATCH "^tp-chain: no MATCHES files given: --images took every name after it \\(the last m.matches\\): put the matches files first, or end the images with --\n$" NO_FILE t.tracks)
