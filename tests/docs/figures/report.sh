# docs/report.md: the page holds every file given, with the figures of each kind
grep -q '<svg' marseille.html || fail "marseille.html: no figure"
for f in pair-1-2.matches pair-1-3.matches pair-2-3.matches triplet.tracks fit-ml.eval rpc.residuals rpc.bias; do
  grep -q "$f" marseille.html || fail "marseille.html: $f not shown"
done
