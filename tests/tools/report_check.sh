#!/bin/bash
# Opens a tp-report page in headless Chromium (absent: FAIL, never skip) and checks what a reader sees:
# the page loads (a screenshot is written, no "ERROR" line about the page or its resources), the
# screenshot has the requested size, and it is not blank: in colour (the figures' viridis cells), with
# a mean below 97% of white (oiiotool --stats, OpenImageIO's tool); and where the page has the summary
# box (tp-report's "at a glance"), its background colour fills a band of its width in the top 600 rows.
# Usage: report_check.sh PAGE.html WIDTH HEIGHT
set -u
page=$1; w=$2; h=$3
fail() { echo "report_check: $page: $*" >&2; exit 1; }
command -v chromium >/dev/null || fail "chromium not found: install it (scripts/install-deps.sh --test)"
command -v oiiotool >/dev/null || fail "oiiotool not found: install openimageio-tools"
grep -qi '<script' "$page" && fail "the page holds a script"
grep -oE '(src|href)="[a-z]+://[^"]*' "$page" | head -1 | grep . && fail "the page loads something from the network"
shot=$PWD/shot.png
rm -f "$shot"
timeout 120 chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --user-data-dir="$PWD/chromium-profile" \
  --screenshot="$shot" --window-size="$w,$h" "file://$(realpath "$page")" > chromium.log 2>&1 ||
  fail "chromium failed: $(tail -5 chromium.log)"
# errors about the page itself (not the sandbox's missing D-Bus)
grep -E 'ERROR|Uncaught' chromium.log | grep -viE 'dbus|bus\.cc|gpu|viz|gcm|sandbox' && fail "chromium reported errors"
[ -s "$shot" ] || fail "no screenshot"
info=$(oiiotool --info -v --stats "$shot" 2>&1)
echo "$info" | grep -q "$w x *$h" || fail "screenshot is not ${w}x${h}: $(echo "$info" | head -1)"
echo "$info" | grep -q 'Monochrome: No' || fail "screenshot has no colour"
avg=$(echo "$info" | awk '/Stats Avg:/ { s = 0; for (i = 3; i <= 5; i++) s += $i; print s / 3; exit }')
awk -v a="$avg" 'BEGIN { exit !(a < 0.97 * 255 && a > 0) }' || fail "screenshot nearly blank (mean $avg of 255)"
echo "page ok: ${w}x${h}, mean $avg"
if grep -q 'id="summary" class="glance"' "$page"; then
  top=$((h < 600 ? h : 600))
  n=$(oiiotool "$shot" --cut "${w}x${top}+0+0" --colorcount:eps=0.004,0.004,0.004 "0.9176,0.9451,0.9804" 2>&1 |
    awk '$2 == "0.9176,0.9451,0.9804" { print $1 }')
  [ "${n:-0}" -gt $((w * 40)) ] || fail "the summary box is not seen at the top of the page (${n:-no} pixels of its colour #eaf1fa)"
  echo "summary box shown: $n pixels"
fi
