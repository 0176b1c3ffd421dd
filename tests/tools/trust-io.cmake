# Trust campaign (issue 50), area "io": images that are no files, devices and pipes as text inputs,
# sizes a file declares, tp-rpc's stream, and the messages for missing files and filesystem errors.
set(_m "$SHARED/data/pleiades-marseille")
set(_syn "tp-synth -o syn --size 256 --points 300 --seed 3 >/dev/null 2>&1")
set(_views "syn/view1.tif syn/view2.tif syn/view3.tif")

# Item 1: an image that is a device or a FIFO is refused at once (it spun at 100% CPU for ever), in every
# tool that opens images, and as the image of a header line given to tp-report or tp-chain --coverage.
tpkit_tool_test(trust-io.image-device-tp-match
  COMMAND "timeout 20 tp-match /dev/zero ${_m}/img_01.tif -o z.matches"
  EXPECT_FAIL STDERR_MATCH "^tp-match: /dev/zero: not a regular file: an image must be a file\n$" NO_FILE z.matches)
tpkit_tool_test(trust-io.image-device-tp-ground
  COMMAND "${_syn} && timeout 20 tp-ground /dev/urandom syn/view2.tif --tracks syn/truth.tracks -o g.points"
  EXPECT_FAIL STDERR_MATCH "^tp-ground: /dev/urandom: not a regular file: an image must be a file\n$" NO_FILE g.points)
tpkit_tool_test(trust-io.image-fifo-rpc-adjust
  COMMAND "${_syn} && mkfifo f.tif && timeout 20 rpc-adjust f.tif syn/view2.tif --tracks syn/truth.tracks -o out"
  EXPECT_FAIL STDERR_MATCH "^rpc-adjust: f.tif: not a regular file: an image must be a file\n$" NO_FILE out)
tpkit_tool_test(trust-io.image-device-tp-plan
  COMMAND "${_syn} && timeout 20 tp-plan -q -o w /dev/zero syn/view2.tif"
  EXPECT_FAIL STDERR_MATCH "^tp-plan: /dev/zero: not a regular file: an image must be a file\n$" NO_FILE w)
tpkit_tool_test(trust-io.image-device-in-a-report-header
  COMMAND "printf '# tpkit matches 1\\n# image1: /dev/zero 100 100\\n# image2: /dev/zero 100 100\\n# columns: id1 x1 y1 id2 x2 y2\\n1 5 5 1 6 6\\n' > z.matches && timeout 20 tp-report z.matches -o page.html && grep -o 'no thumbnail: [a-z]*' page.html | sort -u"
  STDOUT_MATCH "^no thumbnail: unreadable\n$")
tpkit_tool_test(trust-io.image-device-in-chain-coverage
  COMMAND "printf '# tpkit matches 1\\n# image1: /dev/zero 100 100\\n# image2: /dev/urandom 100 100\\n# columns: id1 x1 y1 id2 x2 y2\\n1 5 5 1 6 6\\n' > z.matches && timeout 20 tp-chain -q z.matches --min-views 2 -o t.tracks --coverage cov.svg && grep -o 'no thumbnail: [a-z]*' cov.svg | sort -u"
  STDOUT_MATCH "^no thumbnail: unreadable\n$")

# Item 2: a device as a text input fails at its first line: the header-kind sniffing and the GCP and
# tp-report readers read it whole (/dev/zero: 2.1 GB, then "out of memory"; under a memory limit they
# stopped where memory did, the same message seconds later). A stream of NUL bytes is read no further
# than the first block: its writer is cut off by the closed pipe, never reaching "writer done".
set(_zeros "{ head -c 300000000 /dev/zero 2>/dev/null && echo writer done >&2 @SEMI@ }")
tpkit_tool_test(trust-io.tracks-device-tp-ground
  COMMAND "${_syn} && ${_zeros} | timeout 20 tp-ground ${_views} --tracks - -o g.points"
  EXPECT_FAIL STDERR_MATCH "^tp-ground: <stdin>:1: binary data \\(NUL byte\\) in a text file\n$" NO_FILE g.points)
tpkit_tool_test(trust-io.check-device-rpc-adjust
  COMMAND "${_syn} && ${_zeros} | timeout 20 rpc-adjust ${_views} --tracks syn/truth.tracks --check - -o out"
  EXPECT_FAIL STDERR_MATCH "^rpc-adjust: <stdin>:1: binary data \\(NUL byte\\) in a text file\n$" NO_FILE out)
tpkit_tool_test(trust-io.gcp-device-rpc-adjust
  COMMAND "${_syn} && (ulimit -v 1500000 @SEMI@ timeout 20 rpc-adjust ${_views} --tracks syn/truth.tracks --gcp /dev/zero -o out)"
  EXPECT_FAIL STDERR_MATCH "^rpc-adjust: /dev/zero:1: binary data \\(NUL byte\\) in a text file\n$" NO_FILE out LABELS rlimit)
tpkit_tool_test(trust-io.report-device
  COMMAND "${_zeros} | timeout 20 tp-report /dev/stdin -o page.html && grep -o 'not read: [^<]*' page.html"
  STDOUT_MATCH "^not read: /dev/stdin:1: binary data \\(NUL byte\\) in a text file\n$" STDERR_MATCH "^tp-report: page.html: 1 files, [0-9]+ KiB\n$")
# (a first line without a break, 300 MB of it: the sniff read it whole, 884 MB; now 1 MiB, the line bound)
tpkit_tool_test(trust-io.report-line-without-a-break
  COMMAND "{ head -c 300000000 /dev/zero | tr -c x x && echo writer done >&2 @SEMI@ } | timeout 20 tp-report /dev/stdin -o page.html && grep -o 'not read: [^<]*' page.html"
  STDOUT_MATCH "^not read: /dev/stdin:1: line longer than 1048576 bytes: not a text file\n$" STDERR_MATCH "^tp-report: page.html: 1 files, [0-9]+ KiB\n$")

# Item 3: valid pipes: a process substitution and a named FIFO as --tracks (the sniffing consumed the
# pipe, then opened it again: "headerless input with 1 fields", or a hang), and tp-report reading one.
# A FIFO as --dem is no image: refused at once (it hung in libtiff's open).
tpkit_tool_test(trust-io.tracks-process-substitution
  COMMAND "${_syn} && timeout 60 tp-ground ${_views} --tracks <(cat syn/truth.tracks) -o g.points && grep -vc '^#' g.points"
  STDOUT_MATCH "^300\n$")
tpkit_tool_test(trust-io.tracks-named-fifo
  COMMAND "${_syn} && mkfifo t.fifo && (cat syn/truth.tracks > t.fifo &) && timeout 60 tp-ground ${_views} --tracks t.fifo -o g.points && grep -vc '^#' g.points"
  STDOUT_MATCH "^300\n$")
tpkit_tool_test(trust-io.rpc-adjust-tracks-from-a-pipe
  COMMAND "${_syn} && timeout 60 rpc-adjust ${_views} --tracks <(cat syn/truth.tracks) --model shift --fixed syn/view1.tif -o out 2>/dev/null && grep -c '^# observations: 900$' out/rpc.residuals"
  STDOUT_MATCH "^1\n$")
tpkit_tool_test(trust-io.report-reads-a-pipe
  COMMAND "${_syn} && timeout 60 tp-report --no-coverage <(cat syn/truth.tracks) -o page.html && grep -c 'unreadable' page.html @SEMI@ grep -c '(tracks, 300 records)' page.html"
  STDOUT_MATCH "^0\n1\n$")
tpkit_tool_test(trust-io.dem-fifo
  COMMAND "${_syn} && mkfifo d.tif && echo '10 10' | timeout 20 tp-rpc localize syn/view1.tif --dem d.tif"
  EXPECT_FAIL STDERR_MATCH "^tp-rpc: d.tif: not a regular file: an image must be a file\n$")

# Item 4: sizes a file declares. An rpc-residuals image number outside the header's image lines is
# refused (it drew 100000 panels: 40 s, a 693 MB page); a header's image size is not the thumbnail's
# measure (the image's own is); a crop of a NITF declaring 819200^2 pixels in 40 kB is refused at once.
tpkit_tool_test(trust-io.rpc-residuals-image-out-of-range
  COMMAND "printf '# tpkit rpc-residuals 1\\n# image1: a.tif 100 100\\n# columns: track image x y dx_before dy_before dx_after dy_after flagged sigma\\n1 1 5 5 0 0 0 0 0 1\\n2 100000 5 5 0 0 0 0 0 1\\n' > r.res && timeout 20 tp-report r.res -o page.html && grep -o 'not drawn: [^<]*' page.html && test $(wc -c < page.html) -lt 10000 && echo small page"
  STDOUT_MATCH "^not drawn: r.res:5: image 100000 is not one of the header's image lines \\(1 to 1\\)\nsmall page\n$")
tpkit_tool_test(trust-io.thumbnail-size-from-the-image
  COMMAND "printf '# tpkit matches 1\\n# image1: %s 100 100\\n# image2: %s 100 100\\n# columns: id1 x1 y1 id2 x2 y2\\n1 5 5 1 6 6\\n' ${_m}/img_01.tif ${_m}/img_02.tif > m.matches && timeout 20 tp-report m.matches -o page.html && grep -o 'no thumbnail: the image is [0-9]* x [0-9]*, not 100 x 100' page.html | wc -l"
  STDOUT_MATCH "^2\n$")
# (the issue's own case: 100 x 100 in the header over a NITF of 30000^2 pad blocks, whose thumbnail read
# 3.5 GB; bounded here, where the old read ran out of memory and said "unreadable")
tpkit_tool_test(trust-io.thumbnail-of-a-padded-nitf
  COMMAND "bash $SRC/tests/tools/masked_nitf.sh pad.ntf 30000 30000 1000 && printf '# tpkit matches 1\\n# image1: pad.ntf 100 100\\n# image2: pad.ntf 100 100\\n# columns: id1 x1 y1 id2 x2 y2\\n1 5 5 1 6 6\\n' > m.matches && (ulimit -v 1500000 @SEMI@ timeout 20 tp-report m.matches -o page.html) && grep -o 'no thumbnail: [^<]*' page.html | sort -u"
  STDOUT_MATCH "^no thumbnail: the image is 30000 x 30000, not 100 x 100\n$" LABELS rlimit)
tpkit_tool_test(trust-io.crop-of-a-nitf-declaring-more-than-it-holds
  COMMAND "${_syn} && bash $SRC/tests/tools/masked_nitf.sh big.ntf 819200 819200 8192 && cp syn/view1_rpc.txt big_rpc.txt && timeout 20 tp-rpc crop big.ntf -o c.tif"
  EXPECT_FAIL STDERR_MATCH "^tp-rpc: big.ntf: the window of 819200 x 819200 pixels is more than 1048576 pixels per byte of the file \\(40856 bytes\\)" NO_FILE c.tif)
# (a masked NITF that declares what it can hold is cropped: the check is no refusal of masked images)
tpkit_tool_test(trust-io.crop-of-a-small-masked-nitf
  COMMAND "${_syn} && bash $SRC/tests/tools/masked_nitf.sh small.ntf 100 120 16 && cp syn/view1_rpc.txt small_rpc.txt && tp-rpc crop small.ntf -o c.tif && head -c 2 c.tif"
  STDOUT_MATCH "^II$" STDERR_MATCH "crop 120 x 100 at \\(0, 0\\) of small.ntf")

# Item 16: tp-rpc streams: `yes | tp-rpc project` prints as it reads (it held every line until the
# input ended, growing without bound); a bad line stops the stream there, the lines before it written.
tpkit_tool_test(trust-io.rpc-project-streams
  COMMAND "${_syn} && yes '10 10 0' | timeout 20 tp-rpc -q localize syn/view1.tif | head -n 3 | wc -l"
  STDOUT_MATCH "^3\n$")
tpkit_tool_test(trust-io.rpc-stream-stops-at-a-bad-line
  COMMAND "${_syn} && printf '10 10 0\\n20 20 0\\nx y z\\n30 30 0\\n' | tp-rpc -q localize syn/view1.tif > out.txt @SEMI@ echo \"exit $?\" @SEMI@ wc -l < out.txt"
  STDOUT_MATCH "^exit 1\n2\n$" STDERR_MATCH "tp-rpc: stdin:3: ")
tpkit_tool_test(trust-io.rpc-stream-file-output-atomic
  COMMAND "${_syn} && printf '10 10 0\\n20 20 0\\nx y z\\n' | tp-rpc -q localize syn/view1.tif -o out.txt"
  EXPECT_FAIL STDERR_MATCH "tp-rpc: stdin:3: " NO_FILE out.txt)

# Item 17: messages. A missing image is "no such file" (tp-rpc said "not a TIFF file"); a filesystem
# error is said in the project's words, the file first (libstdc++'s "filesystem error: ..." reached the user).
tpkit_tool_test(trust-io.rpc-missing-image
  COMMAND "echo '1 2 3' | tp-rpc project /nonexistent/x.tif"
  EXPECT_FAIL STDERR_MATCH "^tp-rpc: /nonexistent/x.tif: no such file\n$")
tpkit_tool_test(trust-io.filesystem-error-in-project-words
  COMMAND "mkdir run && ln -s loop run/loop && printf '# tpkit dem-dz 1\\n# columns: a b\\n1 2\\n' > run/g.dz && tp-report run -o page.html"
  EXPECT_FAIL STDERR_MATCH "^tp-report: run/loop: status: Too many levels of symbolic links\n$" NO_FILE page.html)
