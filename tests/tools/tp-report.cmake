# tp-report: one page from a run's folder (tp-synth scene, trifocal fit with a held-out check, an RPC
# adjustment), opened in headless Chromium; missing input refused without a page.
set(_run "tp-synth -o run/syn --size 256 --points 600 --seed 3 --rpc-bias 2:3,-2 >/dev/null 2>&1 && (grep '^#' run/syn/truth.tracks; grep -v '^#' run/syn/truth.tracks | head -400) > run/fit.tracks && (grep '^#' run/syn/truth.tracks; grep -v '^#' run/syn/truth.tracks | tail -200) > run/check.tracks && trifocal-fit -m affine-dlt run/fit.tracks -o run/t.trifocal && reproj-eval run/t.trifocal run/fit.tracks --check run/check.tracks -o run/fit.eval && rpc-adjust run/syn/view1.tif run/syn/view2.tif run/syn/view3.tif --tracks run/syn/truth.tracks --fixed run/syn/view1.tif --model shift -o run/adjusted 2>/dev/null")
tpkit_tool_test(tp-report.run-in-browser
  COMMAND "${_run} && tp-report run -o page.html --title 'synthetic run' && grep -c '<svg ' page.html && test \"$(grep -o 'rmse_px: [0-9.e-]*' page.html | head -1)\" = \"$(grep '^# rmse_px:' run/fit.eval | cut -c3-)\" && echo summary line shown && grep -c 'class=\"note\"[^>]*>RMSE' page.html && bash $SRC/tests/tools/report_check.sh page.html 1400 2400"
  STDOUT_MATCH "^[4-9]\nsummary line shown\n[1-9][0-9]\npage ok: 1400x2400")
tpkit_tool_test(tp-report.blank-page-refused-by-the-check
  COMMAND "printf '<!DOCTYPE html><html><body><p>nothing</p></body></html>' > blank.html && bash $SRC/tests/tools/report_check.sh blank.html 800 600"
  EXPECT_FAIL STDERR_MATCH "no colour|nearly blank")
tpkit_tool_test(tp-report.missing-input
  COMMAND "tp-report nowhere -o page.html"
  EXPECT_FAIL STDERR_MATCH "tp-report: nowhere: no such file or folder" NO_FILE page.html)
tpkit_tool_test(tp-report.unreadable-file-listed
  COMMAND "printf '# tpkit tracks 1\\n# columns: track x1 y1\\n1 2 oops\\n' > bad.tracks && tp-report bad.tracks -o page.html && grep -c 'class=\"error\"' page.html"
  STDOUT_MATCH "^1\n")
# A value a kind writes as nan (a dem-dz file's empty slope class, an accuracy file's point not intersected)
# is shown, not taken for an unreadable file.
tpkit_tool_test(tp-report.nan-values-shown
  COMMAND "printf '# tpkit dem-dz 1\\n# columns: stage class slope_min slope_max count median\\n0 0 0 90 10 0.5\\n0 5 40 90 0 nan\\n' > g.dz && tp-report g.dz -o page.html && grep -c 'class=\"error\"' page.html; grep -c '>nan<\\|nan' page.html"
  STDOUT_MATCH "^0\n[1-9]")
