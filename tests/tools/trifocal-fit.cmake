# trifocal-fit end to end on tp-synth ground truth (exact affine projections of a synthetic triplet):
# fit -> reproj-eval, noise, outliers, and every degenerate input (error, exit 1, no output file).
set(_synth "tp-synth --out syn --size 160 --points 300 --seed 3 --supersample 1 >/dev/null 2>&1")
# Gaussian noise sigma 0.5 px on every coordinate (Box-Muller, fixed seed)
set(_noise "awk 'BEGIN{srand(7)} /^#/{print;next} {for(c=2;c<=7;c++){u=rand();v=rand();if(u<1e-12)u=1e-12;$c+=0.5*sqrt(-2*log(u))*cos(6.283185307179586*v)} print}'")

foreach(m dlt affine-dlt algebraic minimal three-f ml)
  tpkit_tool_test(trifocal-fit.${m}-exact
    COMMAND "${_synth} && trifocal-fit -m ${m} syn/truth.tracks -o t.trifocal && reproj-eval t.trifocal syn/truth.tracks"
    STDOUT_MATCH "# rmse_px: ([0-9.]+e-(0[7-9]|[1-9][0-9])|0)\n" CHECK_FILE t.trifocal FILE_MATCH "# method: ${m}")
endforeach()

# the fitted tensor transfers view-1/view-2 points onto the true view-3 points (< 1e-6 px)
tpkit_tool_test(trifocal-fit.transfer-matches-truth
  COMMAND "${_synth} && trifocal-fit syn/truth.tracks -o t.trifocal && grep -v '^#' syn/truth.tracks | cut -d' ' -f2-5 | reproj-eval --transfer t.trifocal - -o x3.points && grep -v '^#' syn/truth.tracks | cut -d' ' -f6,7 > x3.truth && grep -v '^#' x3.points | paste -d' ' - x3.truth | awk '{d=($1-$3)^2+($2-$4)^2; if(d>m)m=d; n++} END{print n, \"max_err_px\", sqrt(m); exit !(n==300 && sqrt(m)<1e-6)}'"
  STDOUT_MATCH "300 max_err_px")

# sigma = 0.5 px: the ML fit reaches the ML bound sigma sqrt((n-4)/n) = 0.497 px (2-D RMSE), +-5%
tpkit_tool_test(trifocal-fit.ml-noise-at-bound
  COMMAND "${_synth} && ${_noise} syn/truth.tracks > noisy.tracks && trifocal-fit noisy.tracks -o t.trifocal && reproj-eval t.trifocal noisy.tracks | grep '^# rmse_px' | awk '{print; exit !($3 > 0.47 && $3 < 0.52)}'"
  STDOUT_MATCH "# rmse_px: 0[.]")

# every 4th track (by id) gets view 3 moved by 40 px: --ransac finds them, the inlier column says so
tpkit_tool_test(trifocal-fit.ransac-outliers
  COMMAND "${_synth} && ${_noise} syn/truth.tracks | awk '/^#/{print;next} {if($1%4==0){$6+=40}; print}' > dirty.tracks && trifocal-fit --ransac 1.5 --seed 5 --inliers flagged.tracks dirty.tracks -o t.trifocal && awk '/^#/{next} {if($1%4==0){o++; oi+=$NF} else {g++; gi+=$NF}} END{print \"good\", g, \"kept\", gi, \"outliers\", o, \"accepted\", oi; exit !(gi>=0.99*g && oi==0)}' flagged.tracks"
  STDOUT_MATCH "good [0-9]+ kept" CHECK_FILE t.trifocal FILE_MATCH "# inliers: ")

tpkit_tool_test(trifocal-fit.cameras-file
  COMMAND "${_synth} && trifocal-fit -m minimal --cameras c.cameras syn/truth.tracks -o t.trifocal"
  CHECK_FILE c.cameras FILE_MATCH "# view 3\n")

tpkit_tool_test(trifocal-fit.same-seed-same-output
  COMMAND "${_synth} && ${_noise} syn/truth.tracks | awk '/^#/{print;next} {if(NR%3==0){$2+=25}; print}' > d.tracks && trifocal-fit --ransac 1.5 --seed 9 d.tracks -o a.trifocal && trifocal-fit --ransac 1.5 --seed 9 d.tracks -o b.trifocal && cmp a.trifocal b.trifocal && echo same"
  STDOUT_MATCH "same")

# degenerate input: clear message, exit 1, no trifocal file
tpkit_tool_test(trifocal-fit.flat-terrain
  COMMAND "tp-synth --out flat --size 160 --points 300 --relief 0 --supersample 1 >/dev/null 2>&1 && trifocal-fit flat/truth.tracks -o t.trifocal"
  EXPECT_FAIL STDERR_MATCH "flat terrain" NO_FILE t.trifocal)
tpkit_tool_test(trifocal-fit.too-few-tracks
  COMMAND "${_synth} && (grep '^#' syn/truth.tracks; grep -v '^#' syn/truth.tracks | head -6) > few.tracks && trifocal-fit -m dlt few.tracks -o t.trifocal"
  EXPECT_FAIL STDERR_MATCH "at least 7 tracks" NO_FILE t.trifocal)
tpkit_tool_test(trifocal-fit.duplicated-track
  COMMAND "${_synth} && (cat syn/truth.tracks; grep -v '^#' syn/truth.tracks | head -1) > dup.tracks && trifocal-fit dup.tracks -o t.trifocal"
  EXPECT_FAIL STDERR_MATCH "duplicated track" NO_FILE t.trifocal)
tpkit_tool_test(trifocal-fit.non-finite
  COMMAND "${_synth} && awk '/^#/{print;next} !done{$2=\"inf\"; done=1} {print}' syn/truth.tracks > inf.tracks && trifocal-fit inf.tracks -o t.trifocal"
  EXPECT_FAIL STDERR_MATCH "inf.tracks:[0-9]+: field 'x1' is not finite: 'inf'" NO_FILE t.trifocal)
# issue 24: a view not seen is nan in x and y; nan in one of them is refused with its line
tpkit_tool_test(trifocal-fit.half-missing-view
  COMMAND "${_synth} && awk '/^#/{print;next} !done{$2=\"nan\"; done=1} {print}' syn/truth.tracks > nan.tracks && trifocal-fit nan.tracks -o t.trifocal"
  EXPECT_FAIL STDERR_MATCH "nan.tracks:[0-9]+: view 1 has x1 nan and y1 a number: a view not seen is nan in both columns" NO_FILE t.trifocal)
# tracks not seen in all three views (tp-chain --min-views 2) are left out with a count; none seen in all: refused
tpkit_tool_test(trifocal-fit.partial-tracks-left-out
  COMMAND "${_synth} && awk '/^#/{print;next} {n++} n<=40{$6=\"nan\"; $7=\"nan\"} {print}' syn/truth.tracks > part.tracks && trifocal-fit part.tracks -o t.trifocal"
  STDERR_MATCH "warning: part.tracks: 40 tracks not seen in all three views left out; fitting the 260 that are" CHECK_FILE t.trifocal FILE_MATCH "# tpkit trifocal 1")
tpkit_tool_test(trifocal-fit.no-complete-track
  COMMAND "${_synth} && awk '/^#/{print;next} {$6=\"nan\"; $7=\"nan\"} {print}' syn/truth.tracks > part.tracks && trifocal-fit part.tracks -o t.trifocal"
  EXPECT_FAIL STDERR_MATCH "part.tracks: none of its 300 tracks is seen in all three views" NO_FILE t.trifocal)
tpkit_tool_test(trifocal-fit.two-views
  COMMAND "printf '1 2 3 4\\n5 6 7 8\\n9 1 2 3\\n4 5 6 8\\n' > two.tracks && trifocal-fit two.tracks -o t.trifocal"
  EXPECT_FAIL STDERR_MATCH "three views" NO_FILE t.trifocal)
tpkit_tool_test(trifocal-fit.unknown-method
  COMMAND "trifocal-fit -m nope - -o t.trifocal < /dev/null"
  EXPECT_FAIL STDERR_MATCH "unknown method" NO_FILE t.trifocal)
# a stream of zeros with no newline (a device, not a file) fails at once with its reason
tpkit_tool_test(trifocal-fit.zero-device
  COMMAND "timeout 20 trifocal-fit /dev/zero -o t.trifocal"
  EXPECT_FAIL STDERR_MATCH "/dev/zero:1: binary data" NO_FILE t.trifocal)
# a robust fit backed by its own minimal sample alone (random tracks) is no fit, for every method
foreach(m ml affine-dlt algebraic minimal)
  tpkit_tool_test(trifocal-fit.${m}-random-tracks-no-fit
    COMMAND "awk 'BEGIN { srand(7) @SEMI@ print \"# tpkit tracks 1\" @SEMI@ print \"# columns: track x1 y1 x2 y2 x3 y3\" @SEMI@ for (i = 1 @SEMI@ i <= 200 @SEMI@ i++) { printf \"%d\", i @SEMI@ for (k = 0 @SEMI@ k < 6 @SEMI@ k++) printf \" %.3f\", 1000 * rand() @SEMI@ print \"\" } }' > r.tracks && trifocal-fit -m ${m} --ransac 1 r.tracks --inliers f.tracks -o t.trifocal"
    EXPECT_FAIL STDERR_MATCH "ransac: no fit: the best model is supported by [4-7] of 200 tracks" NO_FILE t.trifocal)
endforeach()
tpkit_tool_test(trifocal-fit.ransac-nan
  COMMAND "trifocal-fit --ransac nan - -o t.trifocal < /dev/null"
  EXPECT_FAIL STDERR_MATCH "--ransac: must be a finite number" NO_FILE t.trifocal)
tpkit_tool_test(trifocal-fit.ransac-zero
  COMMAND "${_synth} && trifocal-fit --ransac 0 syn/truth.tracks -o t.trifocal"
  EXPECT_FAIL STDERR_MATCH "--ransac: the inlier threshold must be a positive number" NO_FILE t.trifocal)
# the outputs of one run commit together: a later output that cannot be written leaves no earlier one
tpkit_tool_test(trifocal-fit.outputs-all-or-nothing
  COMMAND "${_synth} && trifocal-fit syn/truth.tracks --cameras missing-dir/c -o fit.trifocal"
  EXPECT_FAIL STDERR_MATCH "missing-dir/c: cannot write: folder missing-dir does not exist" NO_FILE fit.trifocal)
tpkit_tool_test(trifocal-fit.two-outputs-one-path
  COMMAND "${_synth} && trifocal-fit --ransac 1 syn/truth.tracks --inliers same -o same"
  EXPECT_FAIL STDERR_MATCH "--inliers and -o name the same file" NO_FILE same)
tpkit_tool_test(trifocal-fit.output-onto-input
  COMMAND "${_synth} && cp syn/truth.tracks t.tracks && trifocal-fit t.tracks --cameras ./t.tracks -o fit.trifocal @SEMI@ rc=$? @SEMI@ cmp t.tracks syn/truth.tracks && exit $rc"
  EXPECT_FAIL STDERR_MATCH "--cameras ./t.tracks: is also an input of this run" NO_FILE fit.trifocal)
# tracks far from the origin against their spread: the affine methods fit them, the projective ones
# (dlt, three-f) refuse instead of returning a tensor 1e6 px off
set(_offset "awk '/^# columns/ { print \"# columns: track x1 y1 x2 y2 x3 y3\" @SEMI@ next } /^#/ { print @SEMI@ next } { printf \"%s\", $1 @SEMI@ for (i = 2 @SEMI@ i <= 7 @SEMI@ i++) printf \" %.6f\", $i + 1e12 @SEMI@ print \"\" }' syn/truth.tracks > big.tracks")
foreach(m dlt three-f)
  tpkit_tool_test(trifocal-fit.${m}-offset-refused
    COMMAND "${_synth} && ${_offset} && trifocal-fit -m ${m} big.tracks -o t.trifocal"
    EXPECT_FAIL STDERR_MATCH "method ${m}: the view 1 points lie up to 1000000000[0-9.]+ px from the origin" NO_FILE t.trifocal)
endforeach()
tpkit_tool_test(trifocal-fit.affine-dlt-offset-fitted
  COMMAND "${_synth} && ${_offset} && trifocal-fit -m affine-dlt big.tracks -o t.trifocal 2>&1 | grep -o 'rmse [0-9.e-]*' | awk '{ exit !($2 < 0.001) }'")
# three-f on coplanar viewing directions (a single-pass acquisition): refused with its figure; the
# epipolar angle is in the header of every three-f fit
tpkit_tool_test(trifocal-fit.three-f-coplanar-refused
  COMMAND "tp-synth --out s0 --size 160 --points 300 --seed 3 --supersample 1 --cross-track 0 >/dev/null 2>&1 && trifocal-fit -m three-f s0/truth.tracks -o t.trifocal"
  EXPECT_FAIL STDERR_MATCH "three-f: the epipolar lines of two views meet in the third at [0-9.e-]+ deg, below 0.05 deg: the camera centres are \\(nearly\\) collinear" NO_FILE t.trifocal)
tpkit_tool_test(trifocal-fit.three-f-angle-in-header
  COMMAND "tp-synth --out s0 --size 160 --points 300 --seed 3 --supersample 1 --cross-track 0,3,0 >/dev/null 2>&1 && trifocal-fit -m three-f s0/truth.tracks -o t.trifocal"
  CHECK_FILE t.trifocal FILE_MATCH "# epipolar_angle_deg: [0-9.]+\n")
# an output on a device (-o /dev/null, a FIFO) is written in place: renaming a temporary file onto it
# would replace the device node (as root, /dev/null became a regular file)
tpkit_tool_test(trifocal-fit.output-to-a-fifo
  COMMAND "${_synth} && mkfifo f && (cat f > got &) && trifocal-fit syn/truth.tracks --cameras cams -o f && sleep 0.5 && test -p f && grep -q '^# tpkit trifocal 1' got && test -s cams && echo fifo-ok"
  STDOUT_MATCH "fifo-ok")
