# A tracks file with one wrong view in some tracks (rpc-adjust's per-view blunders, issue 51): every 4th
# track of 3 or more views has its last seen view moved 12 px along x (towards the image centre; the
# images are SIZE px wide, default 512). Writes the tracks to stdout and "track view" of each moved view
# to BLUNDERS (default blunders.txt): the truth the dropped views are checked against.
# usage: awk [-v SIZE=512] [-v BLUNDERS=FILE] -f blunder_views.awk truth.tracks > bad.tracks
BEGIN { if (SIZE == "") SIZE = 512; if (BLUNDERS == "") BLUNDERS = "blunders.txt" }
/^# columns:/ { for (i = 3; i <= NF; i++) if ($i ~ /^x[0-9]+$/) views = substr($i, 2) + 0 }
/^#/ { print; next }
{
  n = 0; last = 0
  for (v = 1; v <= views; v++) if ($(2 * v) != "nan") { n++; last = v }
}
n >= 3 && ++k % 4 == 0 {
  x = $(2 * last); $(2 * last) = (x > SIZE / 2 ? x - 12 : x + 12)
  print $1, last > BLUNDERS
}
{ print }
