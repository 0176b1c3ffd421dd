# tp-convert: every format out and back on hand-written matches (values exact in float32), the
# conventions at the conversion point (COLMAP +0.5), bad input with no output, and the real consumer:
# COLMAP reads what we write, and tpkit scores what COLMAP matches (both fail when colmap is missing).
set(_cab "printf '# tpkit matches 1\\n# image1: A.tif 100 80\\n# image2: B.tif 90 90\\n# columns: id1 x1 y1 id2 x2 y2 sigma\\n1 10.25 20.5 7 11.75 21.125 0.05\\n2 30 40 8 31.5 40.25 0.3\\n' > ab.m")
set(_cac "printf '# tpkit matches 1\\n# image1: A.tif 100 80\\n# image2: C.tif 70 60\\n# columns: id1 x1 y1 id2 x2 y2 sigma\\n1 10.25 20.5 3 9.5 19.75 0.2\\n' > ac.m")
set(_cin "${_cab} && ${_cac}")

tpkit_tool_test(tp-convert.asp-round-trip
  COMMAND "${_cin} && tp-convert --to asp ab.m ac.m -o run/run && test $(wc -c < run/run-A__B.match) = 196 && tp-convert --from asp run/run-A__B.match run/run-A__C.match -o back && tp-chain back/A__B.matches back/A__C.matches -o t.tracks"
  STDERR_MATCH "tracks by views: 2:1 3:1"
  CHECK_FILE back/A__B.matches
  FILE_MATCH "# image1: A\n# image2: B\n# source-format: asp\n# source: run/run-A__B.match\n# columns: id1 x1 y1 id2 x2 y2 sigma\n0 10.25 20.5 0 11.75 21.125 0.1000000[0-9]*\n1 30 40 1 31.5 40.25 0.3000000[0-9]*\n$")
tpkit_tool_test(tp-convert.asp-text
  COMMAND "${_cin} && tp-convert --to asp-txt ab.m --min-sigma 0.2 -o p && cat p-A__B.txt && mkdir x && oiiotool --create 100x80 1 -d uint8 -o x/A.tif && tp-convert --from asp-txt p-A__B.txt --images x/A.tif -q -o back"
  STDOUT_MATCH "^10.25 20.5 0.2 11.75 21.125 0.2\n30 40 0.3 31.5 40.25 0.3\n$"
  CHECK_FILE back/A__B.matches FILE_MATCH "# image1: x/A.tif 100 80\n# image2: B\n# source-format: asp-txt\n")
tpkit_tool_test(tp-convert.micmac-both-directions
  COMMAND "${_cin} && tp-convert --to micmac ab.m -o Homol && cat Homol/PastisB.tif/A.tif.txt && tp-convert --from micmac Homol -o back"
  STDOUT_MATCH "^11.75 21.125 10.25 20.5 1\n31.5 40.25 30 40 1\n$"
  CHECK_FILE back/A__B.matches FILE_MATCH "# image1: A.tif\n# image2: B.tif\n.*# columns: id1 x1 y1 id2 x2 y2 weight\n0 10.25 20.5 0 11.75 21.125 1\n1 30 40 1 31.5 40.25 1\n$")
tpkit_tool_test(tp-convert.micmac-dat
  COMMAND "${_cin} && tp-convert --to micmac-dat ab.m ac.m -o Homol && test $(wc -c < Homol/PastisA.tif/B.tif.dat) = 96 && test $(wc -c < Homol/PastisC.tif/A.tif.dat) = 52 && oiiotool --create 7x5 1 -d uint8 -o C.tif && tp-convert --from micmac-dat Homol --images C.tif -o back -q && cat back/C__A.matches"
  STDOUT_MATCH "# image1: C.tif 7 5\n# image2: A.tif\n.*\n0 9.5 19.75 0 10.25 20.5 1\n$")
tpkit_tool_test(tp-convert.openmvg
  COMMAND "${_cin} && tp-convert --to openmvg ab.m ac.m -o mvg && cat mvg/matches.f.txt mvg/C.feat && tp-convert --from openmvg mvg/matches.f.txt -o back"
  STDOUT_MATCH "^0 1\n2\n0 0\n1 1\n0 2\n1\n0 0\n9.5 19.75 1 0\n$"
  CHECK_FILE back/A__C.matches FILE_MATCH "# image1: A.tif 100 80\n# image2: C.tif 70 60\n# source-format: openmvg\n.*\n0 10.25 20.5 0 9.5 19.75\n$")
# COLMAP: +0.5 on the way out, -0.5 back, tpkit ids kept by tpkit_keypoint_ids
tpkit_tool_test(tp-convert.colmap-round-trip
  COMMAND "${_cin} && tp-convert --to colmap ab.m ac.m -o col && head -2 col/keypoints/A.tif.txt | cut -c1-12 && cat col/matches.txt && tp-convert --from colmap --colmap-matches raw col/database.db -o back"
  STDOUT_MATCH "^2 128\n10.75 21 1 0\nA.tif B.tif\n0 0\n1 1\n\nA.tif C.tif\n0 0\n\n$"
  CHECK_FILE back/A__B.matches FILE_MATCH "# image1: A.tif 100 80\n# image2: B.tif 90 90\n# source-format: colmap-raw\n.*# keypoints: 2 2\n# columns: id1 x1 y1 id2 x2 y2\n1 10.25 20.5 7 11.75 21.125\n2 30 40 8 31.5 40.25\n$")
# -o names the folder: a database file's name (X.db) would have become a folder of that name
tpkit_tool_test(tp-convert.colmap-output-named-db
  COMMAND "${_cin} && tp-convert --to colmap ab.m ac.m -o x.db"
  EXPECT_FAIL STDERR_MATCH "^tp-convert: -o x.db: --to colmap writes a folder [(]database.db and the text form in it[)]" NO_FILE x.db)
tpkit_tool_test(tp-convert.colmap-no-verified-pairs
  COMMAND "${_cin} && tp-convert --to colmap ab.m -o col && tp-convert --from colmap col/database.db -o back"
  EXPECT_FAIL STDERR_MATCH "col/database.db: holds no image pair with matches" NO_FILE back)

# bad input: one line naming the file, no output
tpkit_tool_test(tp-convert.truncated-asp
  COMMAND "${_cin} && tp-convert --to asp ab.m -o run/run && head -c 100 run/run-A__B.match > run/cut-A__B.match && tp-convert --from asp run/run-A__B.match run/cut-A__B.match -o back"
  EXPECT_FAIL STDERR_MATCH "\ntp-convert: run/cut-A__B.match: truncated: 2 matches need at least 196 bytes, the file has 100\n$" NO_FILE back)
tpkit_tool_test(tp-convert.counts-disagree
  COMMAND "mkdir -p Homol/PastisA.tif && printf '\\x02\\x00\\x00\\x00\\x03\\x00\\x00\\x00' > Homol/PastisA.tif/B.tif.dat && tp-convert --from micmac-dat Homol -o back"
  EXPECT_FAIL STDERR_MATCH "Homol/PastisA.tif/B.tif.dat: the count says 3 records \\(140 bytes\\), the file has 8 bytes" NO_FILE back)
tpkit_tool_test(tp-convert.database-without-tables
  COMMAND ": > empty.db && tp-convert --from colmap empty.db -o back"
  EXPECT_FAIL STDERR_MATCH "^tp-convert: empty.db: not a COLMAP database: it has no table 'cameras'\n$" NO_FILE back)
tpkit_tool_test(tp-convert.unknown-format
  COMMAND "${_cin} && tp-convert --to colmap4 ab.m -o out"
  EXPECT_FAIL STDERR_MATCH "--to: unknown format 'colmap4' \\(known: asp, asp-txt, micmac, micmac-dat, colmap, openmvg\\)" NO_FILE out)
tpkit_tool_test(tp-convert.to-and-from
  COMMAND "${_cin} && tp-convert --to asp --from asp ab.m -o out"
  EXPECT_FAIL STDERR_MATCH "exactly one of --to and --from" NO_FILE out)
# a failure while writing a folder of several files leaves no folder (C has no size: no COLMAP camera)
tpkit_tool_test(tp-convert.colmap-all-or-nothing
  COMMAND "${_cab} && printf '# tpkit matches 1\\n# image1: A.tif 100 80\\n# image2: C.tif\\n# columns: id1 x1 y1 id2 x2 y2\\n1 1 2 3 4 5\\n' > ac.m && tp-convert --to colmap ab.m ac.m -o out/col"
  EXPECT_FAIL STDERR_MATCH "out/col/database.db: COLMAP needs the size of image C.tif" NO_FILE out)
tpkit_tool_test(tp-convert.same-pair-twice
  COMMAND "${_cin} && cp ab.m ab2.m && tp-convert --to asp ab.m ab2.m -o run/run"
  EXPECT_FAIL STDERR_MATCH "name the same file \\(run/run-A__B.match\\)" NO_FILE run)

# the real consumer (labels colmap, slow: not in the sanitizer run)
tpkit_tool_test(tp-convert.colmap-reads-ours
  COMMAND "bash $SRC/tests/tools/tp-convert-colmap-import.sh"
  STDOUT_MATCH "pair 2-3: tpkit [0-9]+ matches; COLMAP merged: [0-9]+ matches"
  LABELS colmap slow TIMEOUT 300)
tpkit_tool_test(tp-convert.tpkit-scores-colmap
  COMMAND "bash $SRC/tests/tools/tp-convert-colmap-score.sh"
  STDOUT_MATCH "colmap: [0-9]+ triplets.*\ntpkit: [0-9]+ triplets"
  LABELS colmap slow TIMEOUT 600)
# --images orders the COLMAP / OpenMVG images, matched to the headers by file name
tpkit_tool_test(tp-convert.images-order
  COMMAND "${_cin} && tp-convert --to openmvg ab.m ac.m --images x/C.tif A.tif B.tif -o mvg && cat mvg/matches.f.txt"
  STDOUT_MATCH "^1 2\n2\n0 0\n1 1\n0 1\n1\n0 0\n$")
tpkit_tool_test(tp-convert.images-unknown
  COMMAND "${_cin} && tp-convert --to colmap ab.m --images Z.tif -o col"
  EXPECT_FAIL STDERR_MATCH "--images names Z.tif, which no matches file holds" NO_FILE col)
# issue 23: -o is taken lexically (o/new/../run made and left a folder o/new), a matches file without
# image lines cannot name peer files (x-__.match was written), an image stem holding "__" round-trips
# through ASP's PREFIX-IMAGE1__IMAGE2 names only with --images, and a folder as input is named as such
set(_pair "printf '# tpkit matches 1\\n# image1: A.tif 100 100\\n# image2: B.tif 100 100\\n# columns: id1 x1 y1 id2 x2 y2\\n5 10 20 7 11 21\\n' > ab.m")
tpkit_tool_test(tp-convert.output-taken-lexically
  COMMAND "${_pair} && mkdir o && tp-convert --to asp ab.m -o o/new/../run && find o | sort"
  STDOUT_MATCH "^o\no/run-A__B.match\n$")
tpkit_tool_test(tp-convert.asp-needs-image-lines
  COMMAND "printf '# tpkit matches 1\\n# columns: id1 x1 y1 id2 x2 y2\\n5 10 20 7 11 21\\n' > m && tp-convert --to asp m -o x @SEMI@ echo exit $? @SEMI@ ls"
  STDOUT_MATCH "^exit 1\nm\n$" STDERR_MATCH "m: the header names no image1 / image2 lines: a peer format needs the images")
tpkit_tool_test(tp-convert.asp-double-underscore-stem
  COMMAND "tp-synth --out s --size 128 --relief 10 --points 20 >/dev/null && cp s/view1.tif a__b.tif && cp s/view2.tif img_02.tif && printf '# tpkit matches 1\\n# image1: a__b.tif 128 128\\n# image2: img_02.tif 128 128\\n# columns: id1 x1 y1 id2 x2 y2\\n5 10 20 7 11 21\\n' > m && tp-convert -q --to asp m -o x && (tp-convert --from asp x-a__b__img_02.match -o back @SEMI@ echo exit $?) && tp-convert -q --from asp x-a__b__img_02.match --images a__b.tif img_02.tif -o back && grep '^# image' back/*.matches"
  STDOUT_MATCH "exit 1\n# image1: a__b.tif 128 128\n# image2: img_02.tif 128 128\n$" STDERR_MATCH "the name holds '__' 2 times: cannot tell where IMAGE1 ends")
