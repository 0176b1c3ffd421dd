# tp-chain on hand-written matches files: a triplet, a same-position duplicate, a conflict, the
# --images order and bad input.
set(_hdr "# tpkit matches 1\\n# image1: A 100 100\\n# image2: B 100 100\\n# columns: id1 x1 y1 id2 x2 y2 kx2 ky2\\n")
set(_ab "printf '# tpkit matches 1\\n# image1: A 100 100\\n# image2: B 100 100\\n# columns: id1 x1 y1 id2 x2 y2 kx2 ky2\\n5 10 20 7 11.25 21.5 11 21\\n6 10 20 8 11.25 21.5 11 21\\n1 50 50 2 52 51 52 51\\n' > ab.m")
set(_ac "printf '# tpkit matches 1\\n# image1: A 100 100\\n# image2: C 100 100\\n# columns: id1 x1 y1 id2 x2 y2 kx2 ky2\\n5 10 20 9 30.5 40.25 30 40\\n1 50 50 3 60 60 60 60\\n4 70 70 3 60.5 60 60 60\\n' > ac.m")
tpkit_tool_test(tp-chain.triplet
  COMMAND "${_ab} && ${_ac} && tp-chain ab.m ac.m -o t.tracks"
  STDERR_MATCH "tracks by views: 3:1; merged duplicates 1, dropped \\(reference conflict\\) 1"
  CHECK_FILE t.tracks FILE_MATCH "# image1: A 100 100\n# image2: B 100 100\n# image3: C 100 100\n.*# tracks_by_views: 3:1\n# columns: track x1 y1 x2 y2 x3 y3 kp ref\n0 10 20 11.25 21.5 30.5 40.25 5 1\n$")
tpkit_tool_test(tp-chain.images-order
  COMMAND "${_ab} && ${_ac} && tp-chain ab.m ac.m --images C B A"
  STDOUT_MATCH "# image1: C.*\n0 30 40 10.75 21.25 9.5 19.75 9 1\n")
tpkit_tool_test(tp-chain.unknown-image
  COMMAND "${_ab} && tp-chain ab.m --images A Z -o t.tracks"
  EXPECT_FAIL STDERR_MATCH "Z: image given with --images appears in no matches file" NO_FILE t.tracks)
tpkit_tool_test(tp-chain.too-many-views
  COMMAND "${_ab} && tp-chain ab.m --min-views 3 -o t.tracks"
  EXPECT_FAIL STDERR_MATCH "min-views 3 is more than the 2 images" NO_FILE t.tracks)
tpkit_tool_test(tp-chain.bad-record
  COMMAND "printf '# tpkit matches 1\\n# image1: A 1 1\\n# image2: B 1 1\\n# columns: id1 x1 y1 id2 x2 y2\\n1 2 3 4 5\\n' > bad.m && tp-chain bad.m -o t.tracks"
  EXPECT_FAIL STDERR_MATCH "bad.m:5:" NO_FILE t.tracks)
tpkit_tool_test(tp-chain.images-twice
  COMMAND "printf '# tpkit matches 1\\n# image1: a\\n# image2: b\\n# columns: id1 x1 y1 id2 x2 y2\\n' > m && tp-chain m --images a a b -o t.tracks"
  EXPECT_FAIL STDERR_MATCH "--images names a twice" NO_FILE t.tracks)
# issue 23: a tracks file whose header says "matches" is refused (its columns were joined as x1 y1 x2 y2
# with record-index ids), and --min-views below 2 is an option error
tpkit_tool_test(tp-chain.tracks-labelled-matches
  COMMAND "${_ab} && ${_ac} && tp-chain ab.m ac.m -o t.tracks && sed 's/tpkit tracks 1/tpkit matches 1/' t.tracks > fake.m && tp-chain fake.m ab.m -o x.tracks"
  EXPECT_FAIL STDERR_MATCH "tp-chain: fake.m: a matches header over the columns of a tracks file \\(track, x3, ...\\): not a matches file" NO_FILE x.tracks)
tpkit_tool_test(tp-chain.min-views-below-two
  COMMAND "${_ab} && tp-chain ab.m --min-views -5 -o t.tracks @SEMI@ echo exit $?"
  STDOUT_MATCH "exit 2" STDERR_MATCH "--min-views: must be at least 2, got '-5'" NO_FILE t.tracks)
# issue 24: tracks of any subset of the images. With --min-views 2 the 2-view tracks are written too
# (before, only those seen in every image were: a track missing a view could not be written), nan where
# a track is not seen, its reference image in `ref`; the file says version 2 and its counts by length.
set(_bc "printf '# tpkit matches 1\\n# image1: B 100 100\\n# image2: C 100 100\\n# columns: id1 x1 y1 id2 x2 y2 kx2 ky2\\n11 80 80 12 81.5 82 81 82\\n' > bc.m")
tpkit_tool_test(tp-chain.partial-tracks
  COMMAND "${_ab} && ${_ac} && ${_bc} && tp-chain ab.m ac.m bc.m --min-views 2 -o t.tracks"
  STDERR_MATCH "tracks by views: 2:1 3:1; .*written 2 tracks of 2 views or more among 3 images \\(by views: 2:1 3:1\\)"
  CHECK_FILE t.tracks FILE_MATCH "^# tpkit tracks 2\n.*# tracks_by_views: 2:1 3:1\n# columns: track x1 y1 x2 y2 x3 y3 kp ref\n0 10 20 11.25 21.5 30.5 40.25 5 1\n1 nan nan 80 80 81.5 82 11 2\n$")
# four images: the default --min-views is 2, and the partial tracks read back in trifocal-fit's
# selection (none in all three of its views here: refused by name)
set(_cd "printf '# tpkit matches 1\\n# image1: C 100 100\\n# image2: D 100 100\\n# columns: id1 x1 y1 id2 x2 y2 kx2 ky2\\n9 30 40 1 33 44 33 44\\n' > cd.m")
tpkit_tool_test(tp-chain.four-images-default-two-views
  COMMAND "${_ab} && ${_ac} && ${_bc} && ${_cd} && tp-chain ab.m ac.m bc.m cd.m -o t.tracks"
  STDERR_MATCH "written 2 tracks of 2 views or more among 4 images \\(by views: 2:1 4:1\\)"
  CHECK_FILE t.tracks FILE_MATCH "# min_views: 2\n.*\n0 10 20 11.25 21.5 30.5 40.25 33.5 44.25 5 1\n1 nan nan 80 80 81.5 82 nan nan 11 2\n$")
# the LSM sigma of each record is carried to the views (half its variance on each end, summed along
# the path): A-B 0.1 px, A-C 0.2 px, C-D 0.3 px
tpkit_tool_test(tp-chain.sigma-carried
  COMMAND "printf '# tpkit matches 1\\n# image1: A 100 100\\n# image2: B 100 100\\n# columns: id1 x1 y1 id2 x2 y2 sigma\\n5 10 20 7 11 21 0.1\\n' > ab.m && printf '# tpkit matches 1\\n# image1: A 100 100\\n# image2: C 100 100\\n# columns: id1 x1 y1 id2 x2 y2 sigma\\n5 10 20 9 30 40 0.2\\n' > ac.m && printf '# tpkit matches 1\\n# image1: C 100 100\\n# image2: D 100 100\\n# columns: id1 x1 y1 id2 x2 y2 sigma\\n9 30 40 1 33 44 0.3\\n' > cd.m && tp-chain ab.m ac.m cd.m -o t.tracks"
  CHECK_FILE t.tracks FILE_MATCH "# columns: track x1 y1 x2 y2 x3 y3 x4 y4 kp ref sigma1 sigma2 sigma3 sigma4\n0 10 20 11 21 30 40 33 44 5 1 0.07071 0.07071 0.1414 0.255\n$")
# issue 27: --coverage draws where the images have tracks: the one track (the other is a conflict) in
# one of 16 x 16 cells over 100 x 100 px: 255 of 256 cells empty in each image; rendered by rsvg-convert,
# every mark inside its panel; the images (not found) have no thumbnail, said
tpkit_tool_test(tp-chain.coverage
  COMMAND "${_ab} && ${_ac} && tp-chain ab.m ac.m --min-views 2 -o t.tracks --coverage cov.svg && bash $SRC/tests/tools/figure_check.sh cov.svg && grep -c '1 point; 255 of 256 cells without any (100%); no thumbnail: image not found' cov.svg"
  STDOUT_MATCH "figure ok: [0-9]+x[0-9]+\n3\n")
tpkit_tool_test(tp-chain.coverage-is-an-input
  COMMAND "${_ab} && ${_ac} && tp-chain ab.m ac.m -o t.tracks --coverage ab.m"
  EXPECT_FAIL NO_FILE t.tracks)
# issue 51: --rpc-check judges every view through the RPC models after each pair's bias. On a tp-synth
# block (models biased by up to 5 px) with a wrong view in every third track of three views or more, its
# records all agreeing on the wrong point (the loop closure cannot see it): the check drops every wrong
# view and no good one, and the views kept sit on the truth (chain_rpc_check.sh)
tpkit_tool_test(tp-chain.rpc-check-against-truth
  COMMAND "bash $SRC/tests/tools/chain_rpc_check.sh"
  STDOUT_MATCH "no check: ([1-9][0-9]+) wrong views, [1-9][0-9]+ kept; good views lost 0; [^\n]*\nrpc check: [1-9][0-9]+ wrong views, 0 kept; good views lost 0; worst kept view 0\\.[0-2][0-9] px from truth\n# rpc_check: [^\n]*15 image pairs, median sigma 0\\.[01][0-9]* px, bias up to [2-9][.0-9]* px")
tpkit_tool_test(tp-chain.rpc-check-needs-models
  COMMAND "${_ab} && tp-chain ab.m --rpc-check 1 -o t.tracks"
  EXPECT_FAIL STDERR_MATCH "^tp-chain: A: no RPC model: no tag 50844" NO_FILE t.tracks)
tpkit_tool_test(tp-chain.rpc-without-rpc-check
  COMMAND "${_ab} && tp-chain ab.m --rpc A=a_rpc.txt -o t.tracks"
  EXPECT_FAIL STDERR_MATCH "--rpc goes with --rpc-check" NO_FILE t.tracks)
