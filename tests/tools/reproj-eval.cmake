# reproj-eval end to end on tp-synth ground truth: summary lines, --check, --plot, --transfer, errors.
set(_rsynth "tp-synth --out syn --size 160 --points 300 --seed 4 --supersample 1 >/dev/null 2>&1")
set(_split "(grep '^#' syn/truth.tracks; grep -v '^#' syn/truth.tracks | head -200) > fit.tracks && (grep '^#' syn/truth.tracks; grep -v '^#' syn/truth.tracks | tail -100) > held.tracks")

# the true tensor (tp-synth) reprojects the true tracks exactly; every summary line is there
tpkit_tool_test(reproj-eval.truth-tensor-exact
  COMMAND "${_rsynth} && reproj-eval syn/truth.trifocal syn/truth.tracks -o r.txt && grep -E '^# (n|rmse_px|rmse_view1_px|rmse_view2_px|rmse_view3_px|median_px|max_px):' r.txt"
  STDOUT_MATCH "# n: 300\n# rmse_px: ([0-9.]+e-(0[7-9]|[1-9][0-9])|0)\n# rmse_view1_px: .*# max_px: ")

tpkit_tool_test(reproj-eval.check-and-plot
  COMMAND "${_rsynth} && ${_split} && trifocal-fit -m affine-dlt fit.tracks -o t.trifocal && reproj-eval t.trifocal fit.tracks --check held.tracks --plot e.svg -o r.txt && grep -q '^# check_n: 100' r.txt && grep -E '^# check_rmse_px' r.txt"
  STDOUT_MATCH "# check_rmse_px: ([0-9.]+e-(0[7-9]|[1-9][0-9])|0)\n" CHECK_FILE e.svg FILE_MATCH "<svg.*view 3.*residual length")

# one line per track, residual columns, in track order
tpkit_tool_test(reproj-eval.one-line-per-track
  COMMAND "${_rsynth} && trifocal-fit syn/truth.tracks -o t.trifocal && reproj-eval t.trifocal syn/truth.tracks | grep -v '^#' | wc -l"
  STDOUT_MATCH "^300\n")

tpkit_tool_test(reproj-eval.transfer-stdin
  COMMAND "${_rsynth} && grep -v '^#' syn/truth.tracks | head -5 | cut -d' ' -f2-5 | reproj-eval --transfer syn/truth.trifocal | grep -v '^#' | wc -l"
  STDOUT_MATCH "^5\n")

tpkit_tool_test(reproj-eval.two-view-tracks
  COMMAND "${_rsynth} && printf '1 2 3 4\\n5 6 7 8\\n' > two.tracks && reproj-eval syn/truth.trifocal two.tracks -o r.txt"
  EXPECT_FAIL STDERR_MATCH "three views" NO_FILE r.txt)
tpkit_tool_test(reproj-eval.missing-tracks
  COMMAND "${_rsynth} && reproj-eval syn/truth.trifocal -o r.txt"
  EXPECT_FAIL STDERR_MATCH "TRIFOCAL TRACKS" NO_FILE r.txt)
tpkit_tool_test(reproj-eval.bad-trifocal
  COMMAND "printf '1 2 3\\n' > bad.trifocal && printf '1 2 3 4 5 6\\n2 3 4 5 6 7\\n' > t.tracks && reproj-eval bad.trifocal t.tracks -o r.txt"
  EXPECT_FAIL STDERR_MATCH "bad.trifocal" NO_FILE r.txt)
tpkit_tool_test(reproj-eval.transfer-empty-stdin
  COMMAND "tp-synth --out s --size 128 --relief 10 --points 20 >/dev/null 2>&1 && reproj-eval --transfer s/truth.trifocal -o t.points < /dev/null"
  EXPECT_FAIL STDERR_MATCH "empty input" NO_FILE t.points)
# issue 24: tracks not seen in all three views are left out with a count on stderr
tpkit_tool_test(reproj-eval.partial-tracks-left-out
  COMMAND "${_rsynth} && awk '/^#/{print;next} {n++} n<=25{$2=\"nan\"; $3=\"nan\"} {print}' syn/truth.tracks > part.tracks && reproj-eval syn/truth.trifocal part.tracks -o r.txt && grep '^# n:' r.txt"
  STDOUT_MATCH "# n: 275" STDERR_MATCH "warning: part.tracks: 25 tracks not seen in all three views left out; evaluating the 275 that are")
# issue 27: the figure renders (rsvg-convert), every mark inside its panel, one exaggeration, and each
# panel's RMSE equal to the file's summary lines (fit row, then check row)
tpkit_tool_test(reproj-eval.figure-renders-check
  COMMAND "${_rsynth} && ${_split} && trifocal-fit -m affine-dlt fit.tracks -o t.trifocal && reproj-eval t.trifocal fit.tracks --check held.tracks --plot e.svg -o r.txt && bash $SRC/tests/tools/figure_check.sh e.svg --field --rmse r.txt rmse_view1_px rmse_view2_px rmse_view3_px check_rmse_view1_px check_rmse_view2_px check_rmse_view3_px && grep -c '<polyline' e.svg"
  STDOUT_MATCH "exaggeration: vectors ×[0-9.e+]+\nrmse: [^\n]+\nfigure ok: [0-9]+x[0-9]+\n")
tpkit_tool_test(reproj-eval.figure-renders
  COMMAND "tp-synth --out syn --size 256 --points 3000 --seed 5 --supersample 1 >/dev/null 2>&1 && trifocal-fit syn/truth.tracks -o t.trifocal && reproj-eval t.trifocal syn/truth.tracks --plot e.svg -o r.txt && bash $SRC/tests/tools/figure_check.sh e.svg --field --rmse r.txt rmse_view1_px rmse_view2_px rmse_view3_px && grep -c 'class=\"legend\"' e.svg"
  STDOUT_MATCH "figure ok: [0-9]+x[0-9]+\n2\n")
