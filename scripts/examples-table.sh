#!/usr/bin/env bash
# Prints a Markdown table of reprojection RMSE from reproj-eval outputs, with the paper's values beside.
#   examples-table.sh TITLE ROWS METHODS PAPER_SPEC EVAL_PATTERN
#     ROWS          space-separated row keys (e.g. "10 100 1000" or "local global")
#     METHODS       space-separated trifocal-fit methods (columns)
#     PAPER_SPEC    "label:v,v,v;v,v,v;..." one group of values per row for the paper's three columns
#                   (minimizing algebraic error, minimal parameterization, direct linear), or "" for none
#     EVAL_PATTERN  path with @ROW@ and @METHOD@ placeholders, e.g. out/fit-@ROW@-@METHOD@.eval
# Each cell shows the RMSE on the fit points and, after a slash, on the held-out check points.
set -euo pipefail
title=$1 rows=$2 methods=$3 paper=$4 pattern=$5
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
    f=${pattern//@ROW@/$r}
    f=${f//@METHOD@/$m}
    if [ -s "$f" ]; then
      fit=$(value rmse_px "$f")
      chk=$(value check_rmse_px "$f" || true)
      line+=" ${fit:-?}${chk:+ / $chk} |"
    else
      line+=" failed |"
    fi
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
echo
