#!/usr/bin/env bash
# The user-facing text (README.md, docs/, man/) states what the tools do now, not what earlier code did
# or what earlier runs gave: the git log keeps that. A guard against the phrases such sentences take;
# each hit is printed with its file and line.
#   no_history.sh REPO
set -euo pipefail
repo=${1:-$(cd "$(dirname "$0")/../.." && pwd)}
cd "$repo"
phrases='older code|earlier code|previous (code|version|tp-[a-z]+)|the stops before|an earlier (measurement|run)|(before|since|after) (commit )?[0-9a-f]{7}\b|before its [a-z]+ went|not re-?measured|re-measured|used to (be|take|give)|no longer (takes|gives|needs)|renderer before|with OpenCV.s SIFT|three runs gave'
if grep -n -i -E "$phrases" README.md docs/*.md man/*.[157]; then
  echo "no-history: the lines above describe earlier code or earlier runs" >&2
  exit 1
fi
echo "no-history: README.md, $(ls docs/*.md | wc -l) docs pages, $(ls man/*.[157] | wc -l) man pages"
