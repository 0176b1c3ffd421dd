#!/usr/bin/env bash
# One cell of the paper's tables: fits a tensor and evaluates it, recording the outcome.
#   examples-fit.sh BIN METHOD FIT_TRACKS CHECK_TRACKS BASE
# writes BASE.trifocal (trifocal-fit -m METHOD on FIT_TRACKS), BASE.eval and BASE.svg (reproj-eval on the
# fit points, --check on the held-out ones), then BASE.outcome, last: the line "fitted", or
# "refused: MESSAGE" when trifocal-fit refuses the points with exit status 1 (a method that cannot stand
# behind a tensor on them, e.g. three-f on a single-pass triplet, whose camera centres are collinear).
# A refusal is a result the report shows; any other failure (a usage error, a crash, reproj-eval failing
# on a tensor that was written) fails the rule, and no outcome is written.
set -euo pipefail
[ $# -eq 5 ] || { echo "usage: $0 BIN METHOD FIT_TRACKS CHECK_TRACKS BASE" >&2; exit 2; }
bin=$1 method=$2 fit=$3 check=$4 base=$5
rm -f "$base.outcome" "$base.trifocal" "$base.eval" "$base.svg"
err=$(mktemp)
trap 'rm -f "$err"' EXIT
set +e
"$bin/trifocal-fit" -m "$method" "$fit" -o "$base.trifocal" 2> "$err"
status=$?
set -e
cat "$err" >&2
if [ "$status" -eq 1 ]; then
  [ ! -e "$base.trifocal" ] || { echo "$0: trifocal-fit failed but left $base.trifocal" >&2; exit 1; }
  message=$(grep -m1 "^trifocal-fit: " "$err" | sed 's/^trifocal-fit: //')
  [ -n "$message" ] || { echo "$0: trifocal-fit exited 1 without a message" >&2; exit 1; }
  printf 'refused: %s\n' "$message" > "$base.outcome.tmp"
  mv "$base.outcome.tmp" "$base.outcome"
  exit 0
fi
[ "$status" -eq 0 ] || exit "$status"
"$bin/reproj-eval" "$base.trifocal" "$fit" --check "$check" --plot "$base.svg" -o "$base.eval"
echo fitted > "$base.outcome.tmp"
mv "$base.outcome.tmp" "$base.outcome"
