# The whole pipeline through Makefile.examples on a small generated scene: tp-synth -> tp-match (3 pairs)
# -> tp-chain -> tp-sample -> trifocal-fit (every method) -> reproj-eval, plus the cluster figures.
# Checks that every table cell is a number, that a second make run does nothing, and the accuracy of the
# maximum-likelihood fit on the synthetic truth (30 fit points drawn from the tracks: an honest 0.4 px
# match among them, sigma 0.42, puts the RMSE at 0.11 px, hence 0.12).
tpkit_tool_test(pipeline.makefile-examples
  COMMAND "bin=$(dirname $(command -v tp-match)) && make -s -C $SRC -f Makefile.examples -j2 report BIN=$bin OUT=$PWD/out SIZE=384 NPOINTS='10 30' NLOCAL=12 TERRAIN_SIZE=384 > make.log 2>&1 || { tail -40 make.log; exit 1; }; ! grep -q failed out/report.md && grep -c '^| [0-9a-z]* | [0-9]' out/report.md && make -C $SRC -f Makefile.examples report BIN=$bin OUT=$PWD/out SIZE=384 NPOINTS='10 30' NLOCAL=12 TERRAIN_SIZE=384 | grep -q 'Nothing to be done' && awk '/^# rmse_px:/ { r = $3 } /^# check_rmse_px:/ { c = $3 } END { print \"ml rmse\", r, \"check\", c; exit !(r < 0.12 && c < 0.15) }' out/fit-30-ml.eval && test -s out/clusters/fig6.svg && test -s out/fit-30-ml.svg"
  STDOUT_MATCH "ml rmse" TIMEOUT 900 LABELS slow)
# issue 23: a folder given as an input file is named as such by every tool (basic_filebuf::underflow ...
# Is a directory)
tpkit_tool_test(pipeline.folder-as-input
  COMMAND "mkdir d && for t in 'tp-chain d' 'tp-sample d --count 1' 'tp-merge d d' 'tp-convert --to asp d -o x' 'trifocal-fit d' 'reproj-eval d d' 'cluster-homog d d' 'tp-match d d' @SEMI@ do $t 2>&1 @SEMI@ echo \" exit $?\" @SEMI@ done"
  STDOUT_MATCH "^tp-chain: d: is a directory\n exit 1\ntp-sample: d: is a directory\n exit 1\ntp-merge: d: is a directory\n exit 1\ntp-convert: d: is a directory\n exit 1\ntrifocal-fit: d: is a directory\n exit 1\nreproj-eval: d: is a directory\n exit 1\ncluster-homog: d: is a directory\n exit 1\ntp-match: d: is a directory\n exit 1\n$")
