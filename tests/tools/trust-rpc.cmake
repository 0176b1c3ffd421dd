# Trust campaign (issue 50), area rpc: GCP files, rpc-adjust's refusals, tp-rpc project's reach.
# A triplet with a bias on every view (no view fixed), 5 control and 20 check points from its truth
# (bench/gcp_from_truth.awk), left out of the tie tracks; and a triplet with two biased views, the first fixed.
set(tr_synth_gcp "tp-synth -o syn --size 256 --points 300 --rpc-bias 1:4,-3,0.002,-0.001 --rpc-bias 2:-5,2,0.001,0.002 --rpc-bias 3:3,5,-0.002,0.001 > /dev/null && awk -v TIES=syn/ties.tracks -f $SRC/bench/gcp_from_truth.awk syn/truth.tracks > syn/points.gcp")
set(tr_adjust_gcp "rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/ties.tracks")
set(tr_synth "tp-synth -o syn --size 512 --points 400 --rpc-bias 2:6,-8,0.002,-0.001,0.001,0.0015 --rpc-bias 3:-10,4,0.001,0.0005 > /dev/null")
set(tr_adjust "rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/truth.tracks --fixed syn/view1.tif")
# tpkit gcp records: id role lon lat h ...; AWK_EDIT changes every point (a wrong zone, a wrong datum)
set(tr_edit_gcp "awk '/^#/ { print @SEMI@ next } { AWK_EDIT @SEMI@ print }' OFS=' ' syn/points.gcp > syn/edited.gcp")

# Item 9: control points all moved 1 km east (a wrong zone or datum) lie about 2000 px from where the
# delivered models project them: refused before any fit, naming the file and the shift in pixels and
# metres; --force-gcp adjusts with them all the same. (They passed as "agreeing with the tie points".)
string(REPLACE "AWK_EDIT" "$3 += 1000 / (111319.49 * cos($4 * 3.14159265358979 / 180))" tr_east "${tr_edit_gcp}")
tpkit_tool_test(trust-rpc.gcp-all-moved-1km
  COMMAND "${tr_synth_gcp} && ${tr_east} && (${tr_adjust_gcp} --gcp syn/edited.gcp --force-gcp -o forced 2>&1 | grep -c 'warning: --gcp syn/edited.gcp: the points lie') && ${tr_adjust_gcp} --gcp syn/edited.gcp --strict -o adj"
  EXPECT_FAIL STDOUT_MATCH "^1\n$"
  STDERR_MATCH "rpc-adjust: --gcp syn/edited.gcp: the points lie [0-9]+ px \\(median\\) from where the delivered models project them, .*: 25 points, 75 measurements: .* offset -?[0-9.]+, -?[0-9.]+ px = known minus seen (99[0-9]|100[0-9])(\\.[0-9]+)? m east, -?[0-9.]+ m north.* \\(--force-gcp adjusts with them all the same\\)"
  NO_FILE adj)
# Item 9: control heights 49.4 m low (EGM96 heights at Marseille given as ellipsoidal) are named as such: a
# warning, and an error with --strict. The delivered models' own heights are within a few metres.
string(REPLACE "AWK_EDIT" "$5 -= 49.4" tr_geoid "${tr_edit_gcp}")
tpkit_tool_test(trust-rpc.gcp-geoid-heights
  COMMAND "${tr_synth_gcp} && ${tr_geoid} && (${tr_adjust_gcp} --gcp syn/edited.gcp -o warned 2>&1 | grep -c 'geoid heights given as ellipsoidal?') && ${tr_adjust_gcp} --gcp syn/points.gcp --strict -o fine 2> fine.log && grep -c 'on the delivered models: 25 points' fine.log && ${tr_adjust_gcp} --gcp syn/edited.gcp --strict -o adj"
  EXPECT_FAIL STDOUT_MATCH "^1\n1\n$"
  STDERR_MATCH "rpc-adjust: --gcp syn/edited.gcp: their heights lie 4[0-9.]+ m below those the delivered models intersect them at, the geoid undulation there \\(49\\.[0-9]+ m\\): geoid heights given as ellipsoidal\\? \\(--strict\\): "
  NO_FILE adj)
# Item 9: the same GCP file given twice (every point counted twice), by its name or another, and one id in
# two files, are refused with the file (and line).
tpkit_tool_test(trust-rpc.gcp-file-twice
  COMMAND "${tr_synth_gcp} && ln -s points.gcp syn/again.gcp && (${tr_adjust_gcp} --gcp syn/points.gcp --gcp syn/points.gcp -o a @SEMI@ echo rc $?) && (${tr_adjust_gcp} --gcp syn/points.gcp --gcp syn/again.gcp -o b @SEMI@ echo rc $?) && grep -v '^#' syn/points.gcp | head -1 > one && (grep '^#' syn/points.gcp @SEMI@ cat one) > syn/other.gcp && ${tr_adjust_gcp} --gcp syn/points.gcp --gcp syn/other.gcp -o c"
  EXPECT_FAIL STDOUT_MATCH "^rc 1\nrc 1\n$"
  STDERR_MATCH "rpc-adjust: syn/points.gcp: given twice \\(also as syn/points.gcp\\): its points would count twice.*rpc-adjust: syn/again.gcp: given twice \\(also as syn/points.gcp\\).*rpc-adjust: syn/other.gcp:[0-9]+: point [0-9]+ is also syn/points.gcp:[0-9]+: one id is one point"
  NO_FILE c)

# Item 10: a height prior that drags the fit over --flag is named in the error, with both RMS (it said
# "wrong models, wrong tracks, or a --flag too tight", naming neither the prior nor the DEM).
tpkit_tool_test(trust-rpc.prior-drags-the-fit
  COMMAND "${tr_synth} && ${tr_adjust} --height-prior 1000+-0.01 -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: --height-prior 1000\\+-0.01 contradicts the tie points: rms after [0-9.e-]+ px with it, [0-9.e-]+ px without .*@SEMI@ (the fit with it fails: [0-9]+ of 400 tracks keep an RMS above 1 px after the fit|the biases it forces are beyond any delivered model's)"
  NO_FILE adj)
# Item 10: the same for a control point given 1 km off with a 1 mm sigma: the GCPs are named, with the
# worst point (a single point moves no median: the check on the delivered models lets it through).
tpkit_tool_test(trust-rpc.gcp-drags-the-fit
  COMMAND "${tr_synth_gcp} && awk -v TIES=syn/ties.tracks -v BLUNDER=1000 -v SG=0.001 -f $SRC/bench/gcp_from_truth.awk syn/truth.tracks > syn/blunder.gcp && ${tr_adjust_gcp} --gcp syn/blunder.gcp -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: --gcp: the control points contradict the tie points: rms after .* largest normalized GCP residual [0-9.e+]+ sigma at point [0-9]+ .*@SEMI@ the fit with them fails: "
  NO_FILE adj)

# Item 13: project gives nan, not a pixel, for a latitude outside [-90, 90], a longitude outside
# [-180, 360), the antipode and the Earth's centre (ECEF 0 0 0), far outside the model's box; a point of
# the scene still projects.
tpkit_tool_test(trust-rpc.project-out-of-reach
  COMMAND "${tr_synth} && printf '5.4428 1000 150\\n545 43.3 150\\n-174.56 -43.3 150\\n' | tp-rpc project syn/view1.tif && echo '0 0 0' | tp-rpc project syn/view1.tif --crs ecef && grep -v '^#' syn/truth.tracks | head -1 | awk '{ print $11, $12, $13 }' > p && tp-rpc project syn/view1.tif -i p"
  STDOUT_MATCH "^nan nan nan\nnan nan nan\nnan nan nan\nnan nan nan\n-?[0-9][0-9.e+-]* -?[0-9][0-9.e+-]* "
  STDERR_MATCH "warning: 3 points have no solution and are written as nan@SEMI@ the first: stdin:1: latitude 1000 is outside \\[-90, 90\\]")

# Item 17: -o naming the images' folder, where an adjusted model would replace the model read (an
# --rpc sidecar): refused before the fit and before any figure is printed (it printed the DEM check's RMS
# line, then failed on the name), exit 2, nothing written.
tpkit_tool_test(trust-rpc.output-is-a-model-read
  COMMAND "${tr_synth} && (${tr_adjust} --dem syn/truth.dem.tif --rpc syn/view2.tif=syn/view2_rpc.txt -o syn 2> log @SEMI@ echo rc $?) && cat log >&2 && grep -c rms log"
  EXPECT_FAIL STDOUT_MATCH "^rc 2\n0\n$"
  STDERR_MATCH "rpc-adjust: .*syn/view2_rpc.txt"
  NO_FILE syn/rpc.bias)
# Item 17: GCP files: a UTF-8 byte order mark (an editor's) is skipped, '-' reads standard input, and an
# id beyond 2^53 (not held exactly by a double, beyond 64 bits here) is refused with file:line.
tpkit_tool_test(trust-rpc.gcp-bom-stdin-ids
  COMMAND "${tr_synth_gcp} && (printf '\\xEF\\xBB\\xBF' @SEMI@ cat syn/points.gcp) > syn/bom.gcp && ${tr_adjust_gcp} --gcp syn/bom.gcp -o bom 2>&1 | grep -c 'agree with the tie points' && cat syn/points.gcp | ${tr_adjust_gcp} --gcp - -o piped 2>&1 | grep -c 'agree with the tie points' && (${tr_adjust_gcp} --tracks - --gcp - -o twice < syn/points.gcp @SEMI@ echo rc $?) && printf '# ASP\\n123456789012345678901234 43.3 5.4 100 1 1 1 view1.tif 10 20 0.2 0.2\\n' > syn/big.gcp && ${tr_adjust_gcp} --gcp syn/big.gcp -o adj"
  EXPECT_FAIL STDOUT_MATCH "^1\n1\nrc 2\n$"
  STDERR_MATCH "'-' \\(standard input\\) is given more than once.*rpc-adjust: syn/big.gcp:2: id '123456789012345678901234' is beyond 2\\^53"
  NO_FILE adj)

# Item 14: a model that diverges over its image (view2's cubic L^3 term of the sample raised to 0.3: up to
# 80 px at its edges, which no bias model follows) in 160 of 400 tracks: the fit flags 113 of them, fewer
# than half of all, and its models were written with a warning; refused now, naming the image, for half or
# more of the tracks that view one image are flagged. Nothing is written.
tpkit_tool_test(trust-rpc.diverging-model
  COMMAND "${tr_synth} && awk '/^#/ { print @SEMI@ next } { n++ } n % 5 < 3 { $4 = $5 = \"nan\" } { print }' syn/truth.tracks | sed 's/^# tpkit tracks 1/# tpkit tracks 2/' > syn/part.tracks && sed 's/^SAMP_NUM_COEFF_12: .*/SAMP_NUM_COEFF_12: 0.3/' syn/view2_rpc.txt > bad_rpc.txt && rpc-adjust syn/view1.tif syn/view2.tif syn/view3.tif --tracks syn/part.tracks --fixed syn/view1.tif --rpc syn/view2.tif=bad_rpc.txt -o adj"
  EXPECT_FAIL STDERR_MATCH "rpc-adjust: image2 syn/view2.tif: [0-9]+ of the 160 tracks that view it keep an RMS above 1 px after the fit( or lost that view as a blunder \\([0-9]+\\))? \\(its rms [0-9.]+ px before, [0-9.]+ px after\\): its model does not fit them"
  NO_FILE adj)
