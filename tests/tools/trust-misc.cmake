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
