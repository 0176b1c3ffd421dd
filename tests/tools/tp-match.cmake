# tp-match: bad input, no overlap, the synthetic truth (bench_match_accuracy --check) and the real
# Pléiades pair. Synthetic scenes come from tp-synth; the all-nodata image is a PGM written by printf.
set(_pl "$SHARED/data/pleiades-marseille")
tpkit_tool_test(tp-match.not-an-image
  COMMAND "echo hello > x.tif && tp-match x.tif x.tif -o out.matches"
  EXPECT_FAIL STDERR_MATCH "tp-match: x.tif: " NO_FILE out.matches)
tpkit_tool_test(tp-match.missing-file
  COMMAND "tp-match nothing.tif nothing2.tif -o out.matches"
  EXPECT_FAIL STDERR_MATCH "tp-match: nothing.tif: no such file" NO_FILE out.matches)
tpkit_tool_test(tp-match.band-does-not-exist
  COMMAND "tp-synth --out s --size 128 --seed 1 && tp-match s/view1.tif s/view2.tif --band 2 -o out.matches"
  EXPECT_FAIL STDERR_MATCH "band 2 does not exist" NO_FILE out.matches)
tpkit_tool_test(tp-match.all-nodata
  COMMAND "{ printf 'P5\\n64 64\\n255\\n'; head -c 4096 /dev/zero; } > z.pgm && tp-match z.pgm z.pgm --nodata 0 -o out.matches"
  EXPECT_FAIL STDERR_MATCH "every pixel of band 1 is nodata" NO_FILE out.matches)
tpkit_tool_test(tp-match.bad-window
  COMMAND "tp-synth --out s --size 128 --seed 1 && tp-match s/view1.tif s/view2.tif --window 20"
  EXPECT_FAIL STDERR_MATCH "window must be odd")
tpkit_tool_test(tp-match.no-overlap
  COMMAND "tp-synth --out a --size 256 --seed 1 && tp-synth --out b --size 256 --seed 2 && tp-match a/view1.tif b/view2.tif -o out.matches && test $(grep -vc '^#' out.matches) -eq 0"
  STDERR_MATCH "warning: no verified matches" CHECK_FILE out.matches FILE_MATCH "# columns: id1 x1 y1 id2 x2 y2 kx2 ky2 sigma corr")
# Same input and seed, any thread count: the same file.
tpkit_tool_test(tp-match.deterministic
  COMMAND "tp-synth --out s --size 384 --seed 4 && tp-match s/view1.tif s/view2.tif --threads 1 -q -o a.m && tp-match s/view1.tif s/view2.tif --threads 2 -q -o b.m && cmp a.m b.m && test $(grep -vc '^#' a.m) -gt 100")
# The keypoint cache: the second run reads both images' keypoints from it and writes the same file as
# a run without the cache; the guided search finds at least the matches of the global one.
tpkit_tool_test(tp-match.cache
  COMMAND "tp-synth --out s --size 384 --seed 4 && tp-match s/view1.tif s/view2.tif --cache kp -q -o a.m && tp-match s/view1.tif s/view2.tif -q -o b.m && tp-match s/view1.tif s/view2.tif --cache kp -o c.m && cmp a.m b.m && cmp a.m c.m && test $(ls kp/*.sift | wc -l) -eq 2"
  STDERR_MATCH "keypoints [0-9]+ \\(cached\\) / [0-9]+ \\(cached\\)")
tpkit_tool_test(tp-match.guided-vs-global
  COMMAND "tp-synth --out s --size 384 --seed 4 && tp-match s/view1.tif s/view2.tif -q --no-rpc -o g.m && tp-match s/view1.tif s/view2.tif --global -q -o a.m && test $(grep -vc '^#' g.m) -ge $(grep -vc '^#' a.m) && grep -q '^# putative: .*guided: coarse affine F' g.m && grep -q '^# putative: .*; global)' a.m")
# Three images: every pair, each file the same as a run on that pair alone.
tpkit_tool_test(tp-match.every-pair
  COMMAND "tp-synth --out s --size 384 --seed 4 --relief 30 && tp-match s/view1.tif s/view2.tif s/view3.tif -q -o pairs && tp-match s/view2.tif s/view3.tif -q -o b.m && cmp pairs/pair-2-3.matches b.m && test $(grep -vc '^#' pairs/pair-1-3.matches) -gt 50 && test $(ls pairs | wc -l) -eq 3")
tpkit_tool_test(tp-match.every-pair-needs-folder
  COMMAND "tp-synth --out s --size 128 --seed 1 && tp-match s/view1.tif s/view2.tif s/view3.tif"
  EXPECT_FAIL STDERR_MATCH "with more than two images, -o must name a folder")
tpkit_tool_test(tp-match.no-refine
  COMMAND "tp-synth --out s --size 256 --seed 5 && tp-match s/view1.tif s/view2.tif --no-refine -o raw.m && awk '!/^#/ && ($5 != $7 || $6 != $8) {bad++} END {exit bad > 0}' raw.m"
  CHECK_FILE raw.m FILE_MATCH "refinement: none.*# columns: id1 x1 y1 id2 x2 y2 kx2 ky2\n[0-9]")

# A verified match whose refinement is rejected is kept at its keypoint position, marked refined 0 with
# sigma >= --unrefined-sigma, and counted by reason in the header: with --min-corr 0.999 most are
# rejected as low-correlation; every verified match is written; --drop-unrefined drops the same ones,
# counted under "# dropped:"; tp-chain leaves them out unless --unrefined.
tpkit_tool_test(tp-match.unrefined-kept-and-marked
  COMMAND "tp-synth --out s --size 384 --seed 4 && tp-match s/view1.tif s/view2.tif --min-corr 0.999 -q -o k.m && tp-match s/view1.tif s/view2.tif --min-corr 0.999 --drop-unrefined -q -o d.m && v=$(sed -n 's/^# verified: \\([0-9]*\\).*/\\1/p' k.m) && u=$(awk '!/^#/ && $11 == 0' k.m | wc -l) && r=$(awk '!/^#/ && $11 == 1' k.m | wc -l) && test $u -gt 50 && test $((u + r)) -eq $v && awk '!/^#/ && $11 == 0 && ($5 != $7 || $6 != $8 || $9 < 0.5) {bad++} END {exit bad > 0}' k.m && grep -q \"^# unrefined: $u kept at the keypoint position, refined 0, sigma 0.5 px (.*low-correlation [0-9]\" k.m && grep -q \"^# dropped: 0 (none)\" k.m && test $(grep -vc '^#' d.m) -eq $r && grep -q \"^# dropped: $u (.*low-correlation\" d.m && tp-match s/view1.tif s/view3.tif -q -o k13.m && tp-match s/view2.tif s/view3.tif -q -o k23.m && tp-chain k.m k13.m k23.m -o a.t && tp-chain k.m k13.m k23.m --unrefined -o b.t && grep -q '^# unrefined: [1-9][0-9]* matches marked refined 0 left out' a.t && test $(grep -vc '^#' b.t) -gt $(grep -vc '^#' a.t)"
  CHECK_FILE k.m FILE_MATCH "# columns: id1 x1 y1 id2 x2 y2 kx2 ky2 sigma corr refined\n")

# A view 2 with a Gaussian PSF of 1.5 px (tp-synth --blur): the relative blur is estimated from the
# matches (median LSM correlation 0.94 unblurred, 0.999 at 1.25 px) and image 1 blurred by it before
# refinement; a same-sensor pair keeps none; --blur gives it; a bad value is refused.
set(synth_blur "tp-synth --out s --size 384 --relief 20 --points 20 --blur 1.5 > /dev/null")
tpkit_tool_test(tp-match.blur-estimated
  COMMAND "${synth_blur} && tp-match s/view1.tif s/view2.tif -q -o b.m && grep '^# blur' b.m && tp-match s/view1.tif s/view2.tif -q --blur 0 -o n.m && grep '^# blur' n.m && tp-synth --out c --size 256 --relief 20 --points 20 > /dev/null && tp-match c/view1.tif c/view2.tif -q -o c.m && grep '^# blur' c.m"
  STDOUT_MATCH "^# blur: image 1 blurred by a Gaussian of 1\\.[0-9]+ px before refinement \\(estimated: median correlation of the sampled matches 0\\.99[0-9]*, 0\\.9[0-6][0-9]* unblurred\\)\n# blur: none \\(--blur\\)\n# blur: none \\(estimated")
tpkit_tool_test(tp-match.blur-bad-value
  COMMAND "tp-match a.tif b.tif --blur sharp -o x.m"
  EXPECT_FAIL STDERR_MATCH "--blur: auto or a number of pixels in \\[-10, 10\\], got 'sharp'" NO_FILE x.m)

# A view 2 of another date (tp-synth --second-date: another sun's shading, tone curve, seasonal field):
# the local-mean high-pass is chosen from the matches (their spread about their own epipolar lines
# falls by a third); --highpass gives it; a pair of one date keeps none; a bad value is refused. 768²
# (about 430 matches, a sample of 300): at 512² the pair has 75 matches, whose median spread varies by
# about 15% from one detector's matches to another's, more than the 10% gain the choice asks for.
set(synth_date "tp-synth --out s --size 768 --second-date 1 > /dev/null")
tpkit_tool_test(tp-match.highpass-estimated
  COMMAND "${synth_date} && tp-match s/view1.tif s/view2.tif -q -o h.m && grep '^# highpass' h.m && tp-match s/view1.tif s/view2.tif -q --highpass 0 -o n.m && grep '^# highpass' n.m && tp-synth --out c --size 256 --relief 20 --points 20 > /dev/null && tp-match c/view1.tif c/view2.tif -q -o c.m && grep '^# highpass' c.m"
  STDOUT_MATCH "^# highpass: local mean \\(Gaussian of [12] px\\) subtracted from both images before refinement \\(estimated on [0-9]+ sampled matches: spread about their epipolar lines 0\\.0[0-9]* px unfiltered, [0-9.]+ px at 1 px, [0-9.]+ px at 2 px\\)\n# highpass: none \\(--highpass\\)\n# highpass: none \\(estimated")
tpkit_tool_test(tp-match.highpass-bad-value
  COMMAND "tp-match a.tif b.tif --highpass soft -o x.m"
  EXPECT_FAIL STDERR_MATCH "--highpass: auto or a number of pixels in \\[0, 10\\], got 'soft'" NO_FILE x.m)

# These need the benchmark program bench_match_accuracy (not built in the sanitizer build).
if(TPKIT_BENCH)
# The blurred view 2 against the truth: the estimated blur brings the median error of the correct
# matches from 0.21 px (--blur 0) to 0.04 px, and keeps more of them.
tpkit_tool_test(tp-match.blur-accuracy
  COMMAND "${synth_blur} && tp-match s/view1.tif s/view2.tif -q -o b.m && tp-match s/view1.tif s/view2.tif -q --blur 0 -o n.m && bench_match_accuracy --synth s --score b.m 1 2 && bench_match_accuracy --synth s --score n.m 1 2 | sed 's/^/none: /' && bench_match_accuracy --synth s --score b.m 1 2 > b.s && bench_match_accuracy --synth s --score n.m 1 2 > n.s && paste b.s n.s | awk '{for (i = 1; i <= NF; ++i) if ($i == \"median\") m[++k] = $(i + 1)} END {exit !(m[1] < 0.08 && m[3] > 2 * m[1])}'"
  STDOUT_MATCH "correct \\(< 1 px\\) [0-9]+, correct median 0\\.0[0-7]")
# The other date against the truth (768², 400 matches): the chosen high-pass brings the median error of
# the correct matches from 0.118 px (--highpass 0) to 0.079 px.
tpkit_tool_test(tp-match.highpass-accuracy
  COMMAND "tp-synth --out s --size 768 --second-date 1 > /dev/null && tp-match s/view1.tif s/view2.tif -q -o h.m && tp-match s/view1.tif s/view2.tif -q --highpass 0 -o n.m && bench_match_accuracy --synth s --score h.m 1 2 > h.s && bench_match_accuracy --synth s --score n.m 1 2 > n.s && cat h.s && paste h.s n.s | awk '{for (i = 1; i <= NF; ++i) if ($i == \"median\") m[++k] = $(i + 1)} END {exit !(m[1] < 0.09 && m[1] < 0.8 * m[3])}'"
  STDOUT_MATCH "correct \\(< 1 px\\) [0-9]+, correct median 0\\.0[0-8]")
# Accuracy against the synthetic truth: refined median and 90th percentile (pixels) of every pair and
# of the chained triplets; the bench exits 1 when a bound fails.
tpkit_tool_test(tp-match.synth-accuracy
  COMMAND "tp-synth --out s --size 512 --seed 3 --relief 15 && bench_match_accuracy --synth s --threads 2 --check 0.03 0.08"
  STDOUT_MATCH "triplets \\(tp-chain\\): [0-9]+" TIMEOUT 300)
# Steeper terrain (40 m over the 256 m scene): the affine window's curvature bias (0.042/0.110 px)
# breaks the bound; the quadratic stage along the epipolar direction brings it back (0.024/0.061).
tpkit_tool_test(tp-match.synth-accuracy-quadratic
  COMMAND "tp-synth --out s --size 512 --seed 3 --relief 40 && bench_match_accuracy --synth s --threads 2 --quadratic 1 --check 0.03 0.08"
  STDOUT_MATCH "triplets \\(tp-chain\\): [0-9]+" TIMEOUT 300)
# The window's size chosen per pair (--taper auto) against the truth: on gentle relief (15 m over the
# 256 m scene) the larger windows it keeps bring the triplets' median error from 0.0223 px (--taper 3:
# the base size alone) to 0.0186 px; on the building scene, where a larger window straddles walls, no
# pair's error grows by more than 5% (median and p90 of the correct matches): most keep the base size;
# with the fit's mask pair 1-3 takes taper 7 quadratic, median 0.0316 -> 0.0323 px, p90 0.211 -> 0.178
# (a taper-5 affine window, refused, would be 1.6x worse).
tpkit_tool_test(tp-match.size-accuracy
  COMMAND "tp-synth --out s --size 512 --seed 3 --relief 15 > /dev/null && bench_match_accuracy --synth s --threads 2 > a.txt && bench_match_accuracy --synth s --threads 2 --taper 3 > b.txt && grep -h '^  views 2+3  ' a.txt b.txt && awk '/^  views 2\\+3  / {for (i = 1; i <= NF; ++i) if ($i == \"median\") m[++k] = $(i + 1)} END {exit !(k == 2 && m[1] < 0.9 * m[2])}' a.txt b.txt"
  STDOUT_MATCH "views 2\\+3 +count +[0-9]+ +median 0\\.01" TIMEOUT 300)
tpkit_tool_test(tp-match.size-buildings
  COMMAND "tp-synth --out t --size 512 --seed 3 --scene buildings > /dev/null && for p in 12 13 23; do a=\${p%?}; b=\${p#?}; tp-match t/view$a.tif t/view$b.tif -q -o a$p.m && tp-match t/view$a.tif t/view$b.tif -q --taper 3 -o b$p.m && bench_match_accuracy --synth t --score a$p.m $a $b > a$p.s && bench_match_accuracy --synth t --score b$p.m $a $b > b$p.s && paste a$p.s b$p.s | awk '{for (i = 1; i < NF; ++i) if ($i == \"correct\" && $(i + 1) == \"median\") {m[++k] = $(i + 2) + 0@SEMI@ q[k] = $(i + 4) + 0}} END {exit !(k == 2 && m[1] <= 1.05 * m[2] && q[1] <= 1.05 * q[2])}' || exit 1 @SEMI@ grep -h '^# size' a$p.m @SEMI@ done"
  STDOUT_MATCH "^# size: taper [0-9] px" TIMEOUT 300)
# The fit's mask (--fit-mask, default 4): on tp-synth's building scene (walls seen from one side only,
# roofs hiding the ground in one view) every pair's p90 error against the truth falls with it, and no
# pair's median grows by more than 10% (seed 3, 512²: p90 0.130 -> 0.114, 0.215 -> 0.178, 0.194 -> 0.181 px).
tpkit_tool_test(tp-match.fit-mask-buildings
  COMMAND "tp-synth --out t --size 512 --seed 3 --scene buildings > /dev/null && for p in 12 13 23; do a=\${p%?}; b=\${p#?}; tp-match t/view$a.tif t/view$b.tif -q -o a$p.m && tp-match t/view$a.tif t/view$b.tif -q --fit-mask 0 -o b$p.m && grep -q '^# refinement: .* fit mask 4 ' a$p.m && bench_match_accuracy --synth t --score a$p.m $a $b > a$p.s && bench_match_accuracy --synth t --score b$p.m $a $b > b$p.s && paste a$p.s b$p.s | awk '{for (i = 1; i < NF; ++i) if ($i == \"correct\" && $(i + 1) == \"median\") {m[++k] = $(i + 2) + 0@SEMI@ q[k] = $(i + 4) + 0}} END {print m[1], q[1], m[2], q[2]@SEMI@ exit !(k == 2 && q[1] < q[2] && m[1] <= 1.1 * m[2])}' || exit 1 @SEMI@ done"
  TIMEOUT 300)
# The per-match size recheck (--size-recheck, default 0.9) on La Reunion's steep relief, where the pair
# takes taper 7 px quadratic: at least as many matches refined, nearer the RPC epipolar curves (an affine
# bias per image removed) over the refined ones and over every record than with the pair's size alone
# (6479 at 0.1595 px RMS against 6476 at 0.1650; every record 0.182 against 0.188).
set(_reu "$SHARED/data/pleiades-reunion")
tpkit_tool_test(tp-match.size-recheck-reunion
  COMMAND "test -d ${_reu} || exit 0; tp-match ${_reu}/img_01.tif ${_reu}/img_02.tif --threads 2 -q --cache kp -o a.m && tp-match ${_reu}/img_01.tif ${_reu}/img_02.tif --threads 2 -q --cache kp --size-recheck 1 -o b.m && grep -q '^# refinement: .* at a smaller size: ' a.m && bench_epipolar_distance ${_reu}/img_01.tif ${_reu}/img_02.tif a.m | tail -1 > a.s && bench_epipolar_distance ${_reu}/img_01.tif ${_reu}/img_02.tif b.m | tail -1 > b.s && paste a.s b.s | awk '{print@SEMI@ exit !($3 >= $12 && $8 < 0.98 * $17 && $6 < $15)}'"
  STDOUT_MATCH "a.m 6[0-9]+ " TIMEOUT 300)
# The real triplet: three pairs and tp-chain give >= 5000 triplets whose affine ML fit has an RMSE
# <= 0.15 px.
tpkit_tool_test(tp-match.pleiades-triplets
  COMMAND "test -d ${_pl} || exit 0; for p in '1 2' '1 3' '2 3'; do set -- $p; tp-match ${_pl}/img_0$1.tif ${_pl}/img_0$2.tif --threads 2 -q -o $1$2.matches || exit 1; done && tp-chain 12.matches 13.matches 23.matches -o t.tracks && test $(grep -vc '^#' t.tracks) -ge 5000 && bench_match_accuracy --tracks t.tracks --check-rmse 0.15"
  TIMEOUT 600 LABELS slow)
endif()
# OpenCV's pool is sized once, never while tpkit's threads are inside it: the every-pair mode and the
# tiled detector, many runs under a competing load on every core, each run bounded by a timeout, so
# that a hang fails here instead of stalling the suite.
# (before: 5 of 60 such runs died with SIGSEGV inside OpenCV, and the suite once hung here)
tpkit_tool_test(tp-match.threads-stress
  COMMAND "tp-synth --out s --size 384 --seed 4 --relief 30 --points 10 && for k in $(seq $(nproc)) @SEMI@ do (end=$((SECONDS + 300)) @SEMI@ while [ $SECONDS -lt $end ] @SEMI@ do : @SEMI@ done) & done @SEMI@ trap 'kill $(jobs -p) 2>/dev/null' EXIT @SEMI@ for i in $(seq 40) @SEMI@ do timeout 60 tp-match s/view1.tif s/view2.tif s/view3.tif -q --tile 256 --overlap 32 --threads $((2 + i % 3)) -o p$i || { echo \"run $i: exit $?\" @SEMI@ exit 1 @SEMI@ } @SEMI@ cmp p$i/pair-1-3.matches p1/pair-1-3.matches || exit 1 @SEMI@ done @SEMI@ echo stress-ok"
  STDOUT_MATCH "stress-ok" TIMEOUT 900 LABELS slow)
tpkit_tool_test(tp-match.threads-out-of-range
  COMMAND "tp-match a.tif b.tif --threads 70000 -o out.matches"
  EXPECT_FAIL STDERR_MATCH "--threads" NO_FILE out.matches)
tpkit_tool_test(tp-match.nan-option
  COMMAND "tp-match a.tif b.tif --ratio nan -o out.matches"
  EXPECT_FAIL STDERR_MATCH "--ratio: must be a finite number, got 'nan'" NO_FILE out.matches)
tpkit_tool_test(tp-match.inf-nodata
  COMMAND "tp-match a.tif b.tif --nodata inf -o out.matches"
  EXPECT_FAIL STDERR_MATCH "--nodata: must be a finite number" NO_FILE out.matches)
# every-pair: a pair that cannot be written (its name is taken by a folder) fails the run, and the
# pairs already matched are not left behind
tpkit_tool_test(tp-match.every-pair-all-or-nothing
  COMMAND "tp-synth --out s --size 256 --seed 4 --relief 20 --points 10 >/dev/null 2>&1 && mkdir -p pairs/pair-2-3.matches && tp-match s/view1.tif s/view2.tif s/view3.tif -q -o pairs @SEMI@ rc=$? @SEMI@ ls pairs @SEMI@ test ! -e pairs/pair-1-2.matches && test -z \"$(ls pairs | grep tmp)\" && exit $rc"
  EXPECT_FAIL STDERR_MATCH "pair-2-3.matches" NO_FILE pairs/pair-1-2.matches)
# a compressed TIFF cut short is a read error, not an image with fewer keypoints
tpkit_tool_test(tp-match.truncated-zip-tiff
  COMMAND "tp-synth --out s --size 512 --relief 10 --points 10 >/dev/null 2>&1 && head -c $(( $(stat -c %s s/view1.tif) / 2 )) s/view1.tif > half.tif && tp-match half.tif s/view2.tif -o out.matches"
  EXPECT_FAIL STDERR_MATCH "^tp-match: half.tif: (read error|Could not open file): [^\n]+\n$" NO_FILE out.matches)
tpkit_tool_test(tp-match.range-message-short
  COMMAND "tp-match a.tif b.tif --iterations -1 -o out.matches"
  EXPECT_FAIL STDERR_MATCH "^tp-match: --iterations: must be > 0, got '-1' [(]see tp-match --help[)]\n$" NO_FILE out.matches)
# the same image twice has no parallax, which the affine F cannot verify: a 2-D affine map does, the
# file says so, and the refined positions sit on the keypoints
tpkit_tool_test(tp-match.same-image-twice
  COMMAND "tp-synth --out s --size 384 --seed 4 --relief 10 --points 10 >/dev/null 2>&1 && tp-match s/view1.tif s/view1.tif -q -o same.m && grep -q '^# verified: [0-9]* (no parallax: 2-D affine map RANSAC' same.m && awk '!/^#/ { n++ @SEMI@ d = ($2 - $5) ^ 2 + ($3 - $6) ^ 2 @SEMI@ if (d > 1e-4) bad++ } END { print n, \"matches\" @SEMI@ exit !(n > 1000 && bad == 0) }' same.m"
  STDOUT_MATCH "^[0-9]+ matches" STDERR_MATCH "have no parallax")
# an option of two values takes two: the images after it are the images (CLI11 took all four and failed)
tpkit_tool_test(tp-match.height-range-before-the-images
  COMMAND "tp-match --height-range 0 100 ${_pl}/img_01.tif ${_pl}/img_02.tif -q -o hr.m"
  CHECK_FILE hr.m FILE_MATCH "rpc-guided: epipolar curves over 0..100 m")
# a --height-range that misses the terrain is named as the cause, not the overlap (nor the models alone)
tpkit_tool_test(tp-match.height-range-missing-the-terrain
  COMMAND "tp-match ${_pl}/img_01.tif ${_pl}/img_02.tif --height-range 5000 5100 --rpc-guided -q -o none.m && tp-match ${_pl}/img_01.tif ${_pl}/img_02.tif --height-range 5000 5100 -q -o some.m"
  STDERR_MATCH "no verified matches between [^\n]* [(]the RPC epipolar curves over the heights 5000..5100 m [(]--height-range[)] held no geometry[^\n]*\n[^\n]*curves of [^\n]* over the heights 5000..5100 m [(]--height-range[)] held no geometry within 160 px [(]--rpc-max-margin[)]; the images' own coarse stage found one: the height range misses the terrain"
  CHECK_FILE none.m FILE_MATCH "# columns: ")
# RPC-guided search (rpc_guided_matching.hpp): on the Pléiades pair the models in tag 50844 give the
# regions, and the matches are the guided search's to a fraction of a percent; --no-rpc restores the
# coarse stage; a crop has no model of its own, --rpc gives it one (the crop at the origin keeps the
# model's pixels), --rpc-guided refuses an image without one
tpkit_tool_test(tp-match.rpc-guided-pleiades
  COMMAND "tp-match ${_pl}/img_01.tif ${_pl}/img_02.tif -q --cache kp -o rpc.m && tp-match ${_pl}/img_01.tif ${_pl}/img_02.tif -q --cache kp --no-rpc -o plain.m && grep -q '^# putative: [0-9]* (ratio 0.8, mutual@SEMI@ rpc-guided: epipolar curves over 40..1090 m, narrowed' rpc.m && grep -q 'guided: coarse affine F' plain.m && a=$(grep -vc '^#' rpc.m) && b=$(grep -vc '^#' plain.m) && echo \"$a $b\" && [ $((a * 1000)) -ge $((b * 995)) ]"
  STDOUT_MATCH "^[0-9]+ [0-9]+\n$")
tpkit_tool_test(tp-match.rpc-override-for-a-crop
  COMMAND "oiiotool ${_pl}/img_01.tif --cut 300x300+0+0 -o crop.tif && tp-match crop.tif ${_pl}/img_02.tif -q --rpc crop.tif=${_pl}/img_01.tif -o out.m && grep -q 'rpc-guided' out.m && test $(grep -vc '^#' out.m) -gt 800"
  CHECK_FILE out.m)
tpkit_tool_test(tp-match.rpc-guided-without-model
  COMMAND "oiiotool ${_pl}/img_01.tif --cut 300x300+0+0 -o crop.tif && tp-match crop.tif ${_pl}/img_02.tif --rpc-guided -o out.m"
  EXPECT_FAIL STDERR_MATCH "^tp-match: crop.tif: no RPC model: no tag 50844" NO_FILE out.m)
tpkit_tool_test(tp-match.rpc-override-unknown-image
  COMMAND "tp-match ${_pl}/img_01.tif ${_pl}/img_02.tif --rpc other.tif=x_rpc.txt -o out.m"
  EXPECT_FAIL STDERR_MATCH "--rpc other.tif=x_rpc.txt: other.tif is not one of the images" NO_FILE out.m)
tpkit_tool_test(tp-match.no-rpc-and-rpc-guided
  COMMAND "tp-match a.tif b.tif --no-rpc --rpc-guided -o out.m"
  EXPECT_FAIL STDERR_MATCH "--no-rpc and --rpc-guided exclude each other" NO_FILE out.m)
tpkit_tool_test(tp-match.height-range-empty
  COMMAND "tp-match ${_pl}/img_01.tif ${_pl}/img_02.tif --height-range 300 200 -o out.m"
  EXPECT_FAIL STDERR_MATCH "--height-range: LO must be below HI" NO_FILE out.m)
# models off by more than --rpc-margin (tp-synth's view 3 biased by 20 px): the first margin holds no
# geometry, a wider one (40 px) measures the bias, and the search stays on the RPC curves with as many
# matches as the images' own coarse stage finds (issue 51); with --rpc-max-margin 10 the curves hold no
# geometry, the images' coarse stage finds it, and a warning says so; --rpc-guided does not fall back
tpkit_tool_test(tp-match.rpc-biased-widens-or-falls-back
  COMMAND "tp-synth --out s --size 512 --seed 4 --relief 40 --points 10 --rpc-bias 3:20,0 >/dev/null 2>&1 && tp-match s/view1.tif s/view3.tif -q -o wide.m && tp-match s/view1.tif s/view3.tif --rpc-max-margin 10 -o fb.m && grep -q 'guided: coarse affine F.*(the RPC epipolar curves held no geometry within 10 px' fb.m && a=$(grep -vc '^#' wide.m) && b=$(grep -vc '^#' fb.m) && echo \"$a $b\" && [ $b -gt 1000 ] && [ $((a * 100)) -ge $((b * 97)) ] && tp-match s/view1.tif s/view3.tif -q --rpc-guided --rpc-max-margin 10 -o strict.m && test $(grep -vc '^#' strict.m) -eq 0 && grep -o 'bias across the curves [-0-9.]*[.][.][-0-9.]* px.*margin [0-9]* px' wide.m"
  STDOUT_MATCH "bias across the curves -?(18|19|20|21)[.0-9]*\\.\\.-?(18|19|20|21)[.0-9]* px.*margin 40 px" STDERR_MATCH "held no geometry within 10 px [(]--rpc-max-margin[)]")
# Under an address-space limit (as clusters set with ulimit -v) the system refuses most of 1000 worker
# threads: tp-match goes on with those that started, says so once, and writes what one thread writes;
# the every-pair mode's detection thread likewise. (Label rlimit: not under the sanitizers, whose shadow
# memory needs more address space than any such limit.)
tpkit_tool_test(tp-match.threads-under-address-limit
  COMMAND "tp-synth --out s --size 384 --seed 4 && tp-match s/view1.tif s/view2.tif --threads 1 -q -o a.m && (ulimit -v 4000000 && tp-match s/view1.tif s/view2.tif --threads 1000 -q -o b.m) && cmp a.m b.m"
  STDERR_MATCH "tp-match: warning: the system refused a worker thread .*going on with [0-9]+ of the 1000 threads" LABELS rlimit)
tpkit_tool_test(tp-match.every-pair-under-address-limit
  COMMAND "tp-synth --out s --size 256 --seed 4 && tp-match s/view1.tif s/view2.tif s/view3.tif --threads 1 -q -o a && (ulimit -v 4000000 && tp-match s/view1.tif s/view2.tif s/view3.tif --threads 1000 -q -o b) && diff -r a b"
  STDERR_MATCH "refused a worker thread" LABELS rlimit)
# issue 27: --coverage shows where a pair has matches: a 40% nodata band on view 2's left leaves at least its
# 6 columns of 16 cells (96 cells) empty there; every mark inside its panel (figure_check.sh renders it).
tpkit_tool_test(tp-match.coverage
  COMMAND "tp-synth -o s --size 384 --relief 20 --nodata-band 0.4 && tp-match s/view1.tif s/view2.tif --nodata 0 -o m.matches --coverage cov.svg && bash $SRC/tests/tools/figure_check.sh cov.svg && grep -o '[0-9]* of 256 cells without any' cov.svg | sed -n 2p | awk '{ print ($1 >= 96 ? \"band empty\" : \"band covered\"), $1 }'"
  STDOUT_MATCH "band empty [0-9]+"
  CHECK_FILE m.matches
  FILE_MATCH "^# tpkit matches")
tpkit_tool_test(tp-match.coverage-one-pair-only
  COMMAND "tp-synth -o s --size 128 && tp-match s/view1.tif s/view2.tif s/view3.tif -o d --coverage c.svg"
  EXPECT_FAIL STDERR_MATCH "tp-match: --coverage draws one pair's matches" NO_FILE c.svg)
# The sigma predicts the error (issue 52): on a synthetic scene's truth the RMS error divided by the RMS
# sigma lies within [0.7, 1.4] in every decile of sigma, over the matches whose error is below 1 px (the
# calibration of pair_lsm_options was set on the default 1024² scene; this is another seed and size).
# Needs the benchmark program bench_match_accuracy (not built in the sanitizer build; runs in the Release suite).
if(TPKIT_BENCH)
tpkit_tool_test(tp-match.sigma-predicts-error
  COMMAND "tp-synth --out s --size 512 --seed 7 > /dev/null && bench_match_accuracy --synth s --threads 2 --sigma-deciles > d.txt && cat d.txt && awk '/^  decile/ {n++; for (i = 1; i <= NF; ++i) if ($i == \"px:\") r = $(i + 2) + 0; if (r < 0.7 || r > 1.4) bad++} END {exit !(n == 10 && bad == 0)}' d.txt"
  STDOUT_MATCH "sigma deciles" TIMEOUT 300)
endif()
tpkit_tool_test(tp-match.residual-mask-bad-value
  COMMAND "tp-synth --out s --size 128 --seed 1 > /dev/null && tp-match s/view1.tif s/view2.tif --residual-mask -1 -o out.matches"
  EXPECT_FAIL STDERR_MATCH "residual-mask" NO_FILE out.matches)
# Retry windows on a pair of two dates (Jacksonville 009, January, and 018, May: shadows moved): some
# matches whose 21-px window failed are refined at another, the file's RMS distance to the RPC epipolar
# curves over all its matches (an affine bias per image removed) no worse than without retries (+0.005 px),
# and more refined; bad sizes are refused. At the base size (--taper 3): where a larger size is chosen,
# the base size takes most of what it fails before the retry windows do.
if(TPKIT_BENCH)
tpkit_tool_test(tp-match.retry-windows-multidate
  COMMAND "J=$SHARED/data/wv3-jacksonville && tp-match $J/JAX_068_009_RGB.tif $J/JAX_068_018_RGB.tif --threads 2 -q --taper 3 -o r.m && tp-match $J/JAX_068_009_RGB.tif $J/JAX_068_018_RGB.tif --threads 2 -q --taper 3 --retry-windows none -o n.m && grep -o '[0-9]* at a retry window' r.m | awk '{ print ($1 > 0 ? \"retried\" : $1) }' && ! grep -q 'retry window' n.m && for f in r.m n.m@SEMI@ do bench_epipolar_distance $J/JAX_068_009_RGB.tif $J/JAX_068_018_RGB.tif $f --heights -40,80 | tail -1@SEMI@ done | awk 'NR == 1 { r = $3@SEMI@ a = $6 } NR == 2 { print (r > $3 ? \"more refined\" : r \" vs \" $3), (a <= $6 + 0.005 ? \"no less precise\" : a \" vs \" $6) }'"
  STDOUT_MATCH "^retried\nmore refined no less precise\n$" TIMEOUT 300)
# Windows cut at the image's edge (--edge-share, default 0.4) on a pair of two dates (Jacksonville 014 and 018: crops
# of 719 x 789 and 828 x 827 px, so many keypoints lie within a window's reach of an edge): at least 20
# matches more refined than without (measured 25), those matches nearer the RPC epipolar
# curves than at their keypoints (an affine bias per image removed; measured 0.363 -> 0.234 px RMS), and
# the file's RMS over every record lower (0.4066 -> 0.4052 px).
tpkit_tool_test(tp-match.edge-share-multidate
  COMMAND "J=$SHARED/data/wv3-jacksonville && tp-match $J/JAX_068_014_RGB.tif $J/JAX_068_018_RGB.tif --threads 2 -q --cache kp -o e.m && tp-match $J/JAX_068_014_RGB.tif $J/JAX_068_018_RGB.tif --threads 2 -q --cache kp --edge-share 0 -o n.m && grep -q \"at an image's edge, the window cut\" e.m && ! grep -q \"image's edge\" n.m && bench_epipolar_distance $J/JAX_068_014_RGB.tif $J/JAX_068_018_RGB.tif e.m --heights -40,80 --dump e.d | tail -1 > e.s && bench_epipolar_distance $J/JAX_068_014_RGB.tif $J/JAX_068_018_RGB.tif n.m --heights -40,80 --dump n.d | tail -1 > n.s && paste e.s n.s | awk '{ print ($3 >= $12 + 20 ? \"more refined\" : $3 \" vs \" $12), ($6 < $15 ? \"every record nearer\" : $6 \" vs \" $15) }' && paste e.d n.d | awk '!/^#/ && $7 == 1 && $16 == 0 { n++@SEMI@ a += $9 * $9@SEMI@ b += $18 * $18 } END { print (n >= 20 && a < 0.8 * b ? \"edge matches nearer\" : n \" \" a \" vs \" b) }'"
  STDOUT_MATCH "^more refined every record nearer\nedge matches nearer\n$" TIMEOUT 300)
endif()
tpkit_tool_test(tp-match.retry-windows-bad
  COMMAND "tp-synth --out s --size 128 --seed 1 > /dev/null && tp-match s/view1.tif s/view2.tif --retry-windows 15,20 -o out.matches"
  EXPECT_FAIL STDERR_MATCH "--retry-windows '15,20': odd window sizes of 5 to 101 pixels" NO_FILE out.matches)
