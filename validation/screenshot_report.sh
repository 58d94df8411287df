#!/usr/bin/env bash
# Renders a `geardyn run` report (DIR/index.html) in headless Chromium, offline, and saves a
# screenshot: the check that the report is self-contained (no network, plots embedded) and
# reads in a real browser. Needs Debian's chromium (apt-get install chromium).
#   validation/screenshot_report.sh DIR [PNG]      (default PNG: validation/report_screenshot.png)
set -euo pipefail
dir=${1:?usage: validation/screenshot_report.sh DIR [PNG]}
png=${2:-validation/report_screenshot.png}
html="$(realpath "$dir")/index.html"
test -f "$html" || { echo "no report at $html: run geardyn run --out $dir first" >&2; exit 1; }
# Self-contained: nothing loaded from the network.
if grep -Eq '(src|href)="(https?:)?//' "$html"; then
    echo "index.html loads something from the network" >&2
    exit 1
fi
browser=$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)
test -n "$browser" || { echo "no chromium: apt-get install chromium" >&2; exit 1; }
"$browser" --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1280,2200 \
    --screenshot="$png" "file://$html" 2>/dev/null
test -s "$png"
echo "wrote $png"
