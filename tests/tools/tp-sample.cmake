# tp-sample: deterministic draws, held-out complement, box filter, bad input.
set(_mk "printf '# tpkit tracks 1\\n# image1: a.tif 100 100\\n# image2: b.tif 100 100\\n# columns: track x1 y1 x2 y2 w\\n' > t.tracks && for i in $(seq 0 99); do echo \"$i $i $((i % 10)) 1 2 0.5\" >> t.tracks; done")
tpkit_tool_test(tp-sample.draw-and-rest-partition
  COMMAND "${_mk} && tp-sample t.tracks -n 30 --seed 5 --rest rest.tracks -o fit.tracks && test $(grep -vc '^#' fit.tracks) = 30 && test $(grep -vc '^#' rest.tracks) = 70 && cat fit.tracks rest.tracks | grep -v '^#' | sort -n | cut -d' ' -f1 | tr '\\n' ' ' > ids && test \"$(cat ids)\" = \"$(seq 0 99 | tr '\\n' ' ')\" && grep -q '^# columns: track x1 y1 x2 y2 w$' fit.tracks && grep -q '^# image2: b.tif 100 100$' rest.tracks")
tpkit_tool_test(tp-sample.deterministic
  COMMAND "${_mk} && tp-sample t.tracks -n 10 --seed 9 > a && tp-sample - -n 10 --seed 9 < t.tracks > b && cmp a b && tp-sample t.tracks -n 10 --seed 10 > c && ! cmp -s a c")
tpkit_tool_test(tp-sample.box
  COMMAND "${_mk} && tp-sample t.tracks --box 20 0 29.5 100 | grep -v '^#' | cut -d' ' -f1 | tr '\\n' ' '"
  STDOUT_MATCH "^20 21 22 23 24 25 26 27 28 29 $")
tpkit_tool_test(tp-sample.headerless-needs-kind
  COMMAND "printf '1 2 3 4\\n5 6 7 8\\n' | tp-sample -n 1"
  EXPECT_FAIL STDERR_MATCH "tp-sample: <stdin>:1: record before any '# columns:' line")
tpkit_tool_test(tp-sample.headerless-with-kind
  COMMAND "printf '1 2 3 4\\n5 6 7 8\\n' | tp-sample --kind tracks -n 2"
  STDOUT_MATCH "# columns: x1 y1 x2 y2\n1 2 3 4\n5 6 7 8")
tpkit_tool_test(tp-sample.too-many
  COMMAND "${_mk} && tp-sample t.tracks -n 101 -o out.tracks" EXPECT_FAIL
  STDERR_MATCH "asked for 101 records, t.tracks has 100" NO_FILE out.tracks)
tpkit_tool_test(tp-sample.bad-record
  COMMAND "${_mk} && echo '100 1 2 x 4 5' >> t.tracks && tp-sample t.tracks -o out.tracks" EXPECT_FAIL
  STDERR_MATCH "tp-sample: t.tracks:105: field 'x2' is not a number: 'x'" NO_FILE out.tracks)
tpkit_tool_test(tp-sample.rest-and-output-one-path
  COMMAND "tp-synth --out s --size 128 --relief 10 --points 20 >/dev/null 2>&1 && tp-sample s/truth.tracks -n 5 --rest o -o o"
  EXPECT_FAIL STDERR_MATCH "--rest and -o name the same file" NO_FILE o)
# a closed or empty stdin is no input: no empty output with exit 0
tpkit_tool_test(tp-sample.empty-stdin
  COMMAND "tp-sample - -n 5 -o o.tracks < /dev/null"
  EXPECT_FAIL STDERR_MATCH "<stdin>: empty input" NO_FILE o.tracks)
tpkit_tool_test(tp-sample.negative-seed
  COMMAND "tp-sample - --seed -1 -o o.tracks < /dev/null"
  EXPECT_FAIL STDERR_MATCH "--seed: must be a non-negative integer, got '-1'" NO_FILE o.tracks)
# issue 23: a tracks file labelled "matches" is no matches file
tpkit_tool_test(tp-sample.tracks-labelled-matches
  COMMAND "printf '# tpkit matches 1\\n# image1: A 9 9\\n# image2: B 9 9\\n# image3: C 9 9\\n# columns: track x1 y1 x2 y2 x3 y3\\n0 1 1 2 2 3 3\\n1 4 4 5 5 6 6\\n' > fake.m && tp-sample fake.m --count 1 -o s.m"
  EXPECT_FAIL STDERR_MATCH "tp-sample: fake.m: a matches header over the columns of a tracks file" NO_FILE s.m)
