#!/bin/bash
# Checks the figures of a tp-report page's summary box against the run's files, computed here from them
# with awk (counts from the records, statistics from the summary lines the writing tool put there):
#   report_summary_check.sh PAGE.html [--matches M1 M2 ...] [--tracks T] [--residuals RPC.RESIDUALS] [--accuracy ACC]
# Prints one "ok KEY" line per figure checked; exits 1 naming the first that differs.
set -u
page=$1; shift
fail() { echo "report_summary_check: $*" >&2; exit 1; }
[ -s "$page" ] || fail "$page: no page"
# the text of the box's cell with this id
cell() { grep -o "id=\"$1\">[^<]*" "$page" | head -1 | cut -d'>' -f2; }
# a summary line's value, as written ("# key: value"), and as the box rounds a statistic: 3 significant
# digits, whole units from 1000 on
line() { sed -n "s/^# $1: //p" "$2" | head -1; }
stat() { awk -v v="$(line "$1" "$2")" 'BEGIN { x = v + 0; printf((x >= 1000 || x <= -1000) ? "%.0f" : "%.3g", x) }'; }
same() {  # KEY EXPECTED
  local got; got=$(cell "$1")
  [ "$got" = "$2" ] || fail "$1: the page says '$got', the files '$2'"
  echo "ok $1"
}
matches=() tracks="" residuals="" accuracy=""
while [ $# -gt 0 ]; do
  case $1 in
    --matches) shift; while [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; do matches+=("$1"); shift; done ;;
    --tracks) tracks=$2; shift 2 ;;
    --residuals) residuals=$2; shift 2 ;;
    --accuracy) accuracy=$2; shift 2 ;;
    *) fail "unknown argument $1" ;;
  esac
done
grep -q 'id="summary" class="glance"' "$page" || fail "$page: no summary box"
# the box comes before the first file's header dump
box=$(grep -n 'id="summary"' "$page" | head -1 | cut -d: -f1)
dump=$(grep -n '<pre class="summary">' "$page" | head -1 | cut -d: -f1)
[ -z "$dump" ] || [ "$box" -lt "$dump" ] || fail "the summary box (line $box) comes after the header dumps (line $dump)"
if [ ${#matches[@]} -gt 0 ]; then
  expect=$(awk '
    FNR == 1 { files++; n[files] = 0; rc = 0 }
    /^# columns:/ { for (i = 3; i <= NF; i++) if ($i == "refined") rc = i - 2 }
    /^#/ { next }
    { n[files]++; total++; if (rc) { with++; if ($rc == 1) refined++ } }
    END {
      lo = n[1]; hi = n[1]
      for (f = 1; f <= files; f++) { if (n[f] < lo) lo = n[f]; if (n[f] > hi) hi = n[f] }
      s = total " matches in " files (files == 1 ? " pair" : " pairs")
      if (files > 1) s = s " (" lo " to " hi " per pair)"
      if (with) s = s sprintf(", %.1f%% refined", 100 * refined / with)
      print s
    }' "${matches[@]}")
  same s-matches "$expect"
fi
if [ -n "$tracks" ]; then
  expect=$(awk '
    /^# columns:/ { for (i = 3; i <= NF; i++) if ($i ~ /^x[0-9]+$/) xc[++nx] = i - 2 }
    /^#/ { next }
    { seen = 0; for (k = 1; k <= nx; k++) if ($xc[k] != "nan") seen++; by[seen]++; n++ }
    END {
      s = n " tracks ("; sep = ""
      for (v = 0; v <= nx; v++) if (v in by) { s = s sep v " views: " by[v]; sep = ", " }
      print s ")"
    }' "$tracks")
  same s-tracks-1 "$expect"
fi
if [ -n "$residuals" ]; then
  n=$(grep -vc '^#' "$residuals")
  same s-adjustment-1 "rms $(stat rms_before_px "$residuals") px before, $(stat rms_after_px "$residuals") px after ($(stat rms_after_unflagged_px "$residuals") px without the flagged tracks), $n observations"
  f=$(line flagged_tracks "$residuals"); t=$(line tracks "$residuals")
  same s-flagged-1 "$f of $t tracks ($(awk -v f="$f" -v t="$t" 'BEGIN { printf "%.1f%%", 100 * f / t }'))"
fi
if [ -n "$accuracy" ]; then
  a() { stat "check_$1" "$accuracy"; }
  same s-check-1 "$(line check_after_n "$accuracy") check points: horizontal rmse $(a before_rmse_h_m) m before, $(a after_rmse_h_m) m after; vertical $(a before_rmse_v_m) m before, $(a after_rmse_v_m) m after"
fi
