#!/usr/bin/env bash
# Prints a Markdown table of reprojection RMSE from reproj-eval outputs, with the paper's values beside.
#   examples-table.sh TITLE ROWS METHODS PAPER_SPEC EVAL_PATTERN
#     ROWS          space-separated row keys (e.g. "10 100 1000" or "local global")
#     METHODS       space-separated trifocal-fit methods (columns)
#     PAPER_SPEC    "label:v,v,v;v,v,v;..." one group of values per row for the paper's three columns
#                   (minimizing algebraic error, minimal parameterization, direct linear), or "" for none
#     BASE_PATTERN  the cells' files without extension, with @ROW@ and @METHOD@ placeholders, e.g.
#                   out/fit-@ROW@-@METHOD@ (BASE.outcome and BASE.eval, written by examples-fit.sh)
# Each cell shows the RMSE on the fit points and, after a slash, on the held-out check points; a method
# that refused the points shows "refused", the first angle of its message if it gives one, and a note
# number, the notes (the whole messages) following the table. A cell without an outcome file is "missing".
set -euo pipefail
[ $# -eq 5 ] || { echo "usage: $0 TITLE ROWS METHODS PAPER_SPEC BASE_PATTERN" >&2; exit 2; }
title=$1 rows=$2 methods=$3 paper=$4 pattern=$5
notes=()
value() {  # value KEY FILE -> the number on the line "# KEY: number ..."
  awk -v k="# $1:" 'index($0, k) == 1 { printf "%.3f\n", $3; exit }' "$2"
}
echo "### $title"
echo
header="| points |"
sep="|---|"
for m in $methods; do header+=" $m |"; sep+="---|"; done
if [ -n "$paper" ]; then
  label=${paper%%:*}
  header+=" paper: algebraic | paper: minimal | paper: DLT |"
  sep+="---|---|---|"
  IFS=';' read -r -a paper_rows <<< "${paper#*:}"
fi
echo "$header"
echo "$sep"
i=0
for r in $rows; do
  line="| $r |"
  for m in $methods; do
    base=${pattern//@ROW@/$r}
    base=${base//@METHOD@/$m}
    outcome=$(head -n 1 "$base.outcome" 2>/dev/null || true)
    case $outcome in
      fitted)
        fit=$(value rmse_px "$base.eval")
        chk=$(value check_rmse_px "$base.eval" || true)
        line+=" ${fit:-?}${chk:+ / $chk} |" ;;
      refused:*)
        message=${outcome#refused: }
        angle=$(grep -oE '[0-9]+(\.[0-9]+)?(e-?[0-9]+)? deg' <<< "$message" | head -n 1 || true)
        notes+=("$r points, $m: $message")
        line+=" refused${angle:+ ($angle)} [${#notes[@]}] |" ;;
      *) line+=" missing |" ;;
    esac
  done
  if [ -n "$paper" ]; then
    IFS=',' read -r -a pv <<< "${paper_rows[$i]:-,,}"
    line+=" ${pv[0]:-} | ${pv[1]:-} | ${pv[2]:-} |"
  fi
  echo "$line"
  i=$((i + 1))
done
echo
[ -n "$paper" ] && echo "Cells: RMSE (px) on the fit points / on the held-out check points. Paper values: $label."
for k in "${!notes[@]}"; do
  echo
  echo "[$((k + 1))] refused, $(sed 's/|/\\|/g' <<< "${notes[$k]}")"
done
echo
