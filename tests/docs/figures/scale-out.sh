# docs/scale-out.md: the plan ran to its results; about 99.9% of the whole run's matches alike (within 0.001 px)
for f in run1/plan.mk run1/tracks.tracks run1/refined.tracks run1/adjusted/rpc.bias run1/ground.points; do
  [ -s "$f" ] || fail "$f: not written"
done
read -r same n < <(sed -n 's/^\([0-9]*\) of \([0-9]*\) matches with the same ids and positions within 0.001 px$/\1 \2/p' "$log")
within "$(awk -v s="${same:-0}" -v n="${n:-1}" 'BEGIN { print s / n }')" 0.995 1 ||
  fail "whole.matches: ${same:-?} of ${n:-?} alike, the page says about 99.9%"
