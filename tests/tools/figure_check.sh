#!/bin/bash
# Checks one tpkit SVG figure (issue 27): it renders with a real SVG renderer (librsvg's rsvg-convert;
# absent: FAIL, never skip) to a PNG of the SVG's size; every mark (line, circle, rect, polyline inside a
# panel's data-p group) lies inside its panel's box; with --field, the figure states exactly one
# exaggeration ("vectors xE"); with --rmse FILE KEY..., the panels' "RMSE v px" notes, in panel order,
# equal FILE's "# KEY: value" summary lines printed to 4 significant digits.
# Usage: figure_check.sh FIG.svg [--field] [--rmse FILE KEY...]
set -u
fail() { echo "figure_check: $svg: $*" >&2; exit 1; }
svg=$1; shift
field=0; rmse_file=; keys=()
while [ $# -gt 0 ]; do
  case $1 in
    --field) field=1; shift ;;
    --rmse) rmse_file=$2; shift 2; keys=("$@"); break ;;
    *) fail "unknown argument $1" ;;
  esac
done
[ -s "$svg" ] || fail "missing or empty"
command -v rsvg-convert >/dev/null || fail "rsvg-convert not found: install librsvg2-bin (scripts/install-deps.sh --test)"
png=${svg%.svg}.check.png
rsvg-convert -b white "$svg" -o "$png" 2> render.err || fail "rsvg-convert failed: $(cat render.err)"
[ ! -s render.err ] || fail "rsvg-convert warned: $(cat render.err)"
# the PNG's size (IHDR) against the SVG's width/height
read -r pw ph < <(od -An -tu1 -j16 -N8 "$png" | awk '{print $1*16777216+$2*65536+$3*256+$4, $5*16777216+$6*65536+$7*256+$8}')
sw=$(grep -o '<svg [^>]*' "$svg" | sed -n 's/.* width="\([0-9.]*\)".*/\1/p')
sh=$(grep -o '<svg [^>]*' "$svg" | sed -n 's/.* height="\([0-9.]*\)".*/\1/p')
awk -v a="$pw" -v b="$sw" -v c="$ph" -v d="$sh" 'BEGIN { exit !(a > 0 && c > 0 && (a - b)^2 < 4 && (c - d)^2 < 4) }' ||
  fail "PNG is ${pw}x${ph}, SVG ${sw}x${sh}"
# marks inside their panels (0.6 page units of tolerance: coordinates are written to 0.01, strokes aside)
awk '
  function attr(s, k,   m) { if (match(s, " " k "=\"[-0-9.e]+\"")) { m = substr(s, RSTART, RLENGTH); sub(/.*="/, "", m); sub(/"$/, "", m); return m + 0 } return "" }
  function chk(x, y) { if (x < X0[p] - 0.6 || x > X1[p] + 0.6 || y < Y0[p] - 0.6 || y > Y1[p] + 0.6) { bad++; if (bad < 4) print "outside panel " p ": " x "," y ": " $0 > "/dev/stderr" } n++ }
  /<rect class="panel"/ { q = attr($0, "data-p"); X0[q] = attr($0, "x"); Y0[q] = attr($0, "y"); X1[q] = X0[q] + attr($0, "width"); Y1[q] = Y0[q] + attr($0, "height"); next }
  /<g data-p=/ { p = attr($0, "data-p"); depth = 1; next }
  p != "" && /<g / { depth++; next }
  p != "" && /<\/g>/ { if (--depth == 0) p = ""; next }
  p != "" && /<line / { chk(attr($0, "x1"), attr($0, "y1")); chk(attr($0, "x2"), attr($0, "y2")) }
  p != "" && /<circle / { r = attr($0, "r"); chk(attr($0, "cx") - r, attr($0, "cy") - r); chk(attr($0, "cx") + r, attr($0, "cy") + r) }
  p != "" && /<rect / { chk(attr($0, "x"), attr($0, "y")); chk(attr($0, "x") + attr($0, "width"), attr($0, "y") + attr($0, "height")) }
  p != "" && /<polyline / { s = $0; sub(/.*points="/, "", s); sub(/".*/, "", s); k = split(s, pt, /[ ,]+/); for (i = 1; i + 1 <= k; i += 2) if (pt[i] != "") chk(pt[i], pt[i + 1]) }
  END { print "marks checked: " n ", outside: " bad + 0; exit (bad > 0 || n == 0) }' "$svg" || fail "marks outside their panel (or none)"
if [ $field = 1 ]; then
  ex=$(grep -o 'vectors ×[0-9.e+-]*' "$svg" | sort -u)
  [ "$(printf '%s\n' "$ex" | grep -c .)" = 1 ] || fail "expected one exaggeration, found: $ex"
  echo "exaggeration: $ex"
fi
if [ -n "$rmse_file" ]; then
  got=$(grep -o 'class="note"[^>]*>RMSE [^ ]*' "$svg" | sed 's/.*RMSE //')
  want=$(for k in "${keys[@]}"; do awk -v k="# $k:" 'index($0, k) == 1 { printf "%.4g\n", $NF; f = 1 } END { exit !f }' "$rmse_file" || echo "no-$k"; done)
  [ "$got" = "$want" ] || fail "panels' RMSE $(echo $got) differ from $rmse_file's $(echo $want)"
  echo "rmse: $(echo $got)"
fi
echo "figure ok: ${pw}x${ph}"
