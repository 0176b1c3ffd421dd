#!/usr/bin/env bash
# The man pages as man(1) renders them: groff reports no warning (a line it cannot adjust, an unknown
# macro, a bad escape), and no option is described twice; the overview tpkit(7) names every page. Each tool's --help is this page (run_tool), so
# what is checked here is also what --help prints.
#   man_pages.sh [SOURCE_DIR]
set -euo pipefail
src=${1:-$(cd "$(dirname "$0")/../.." && pwd)}
command -v groff >/dev/null || { echo "man_pages: groff is missing (Debian groff-base; scripts/install-deps.sh --test)"; exit 1; }
bad=0
for page in "$src"/man/*.[1-8]; do
  name=${page#"$src"/}
  warnings=$(groff -man -Tutf8 -ww -z "$page" 2>&1 || true)
  if [ -n "$warnings" ]; then
    echo "$warnings" | sed "s#^#man_pages: #"
    bad=1
  fi
  # an option item is a .TP followed by a line naming the option (.B/.BR/.BI \-x ...): each once
  dups=$(awk '/^\.TP/ { tp = 1; next }
              tp && /^\.(B|BR|BI|IR) +"?\\-/ {
                # the option names only: ".B \-h, \-\-help" and ".BR \-h \", \" \-\-help" are one item
                line = $0; sub(/^\.[A-Z]+ +/, "", line); gsub(/[\\"]/, "", line)
                n = split(line, w, /[ ,]+/); key = ""
                for (i = 1; i <= n; i++) if (w[i] ~ /^-/) key = key " " w[i]
                print key
              }
              { tp = 0 }' "$page" | sort | uniq -d)
  if [ -n "$dups" ]; then
    echo "$dups" | sed "s#^#man_pages: $name: described twice: #"
    bad=1
  fi
done
# the overview, tpkit(7), names every tool's page and the formats page (.BR NAME (SECTION))
for page in "$src"/man/*.[15]; do
  name=$(basename "$page"); sec=${name##*.}; name=${name%.*}
  grep -qxF ".BR $name ($sec)," "$src/man/tpkit.7" || grep -qxF ".BR $name ($sec)" "$src/man/tpkit.7" ||
    { echo "man_pages: man/tpkit.7: does not name $name($sec)"; bad=1; }
done
[ $bad = 0 ] && echo "man_pages: $(ls "$src"/man/*.[1-8] | wc -l) pages, no groff warning, no option described twice"
exit $bad
