#!/usr/bin/env bash
# Opens <results folder>/report.html in headless chromium (from the file system, network closed,
# fresh profile) with `?selftest`: the page clicks a numeric table heading twice and reads the
# order back, renders its first 3-D view to an image and counts the drawn pixels, and records every
# script error (a script that failed to load included). Passes when the page says "pass" and
# chromium's console log holds no uncaught exception.
# Usage: [VIEW_PNG=view.png] scripts/check_report_html.sh results/thesis_quick
set -euo pipefail
folder="${1:?usage: $0 <results folder with report.html>}"
page="$(cd "$folder" && pwd)/report.html"
[ -f "$page" ] || { echo "no $page"; exit 1; }
browser="${CHROMIUM:-$(command -v chromium || command -v chromium-browser || true)}"
[ -n "$browser" ] || { echo "chromium not found: run scripts/install_chromium.sh"; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# WebGL without a GPU: chromium's software renderer (SwiftShader) must be allowed explicitly.
start=$(date +%s)
set +e
timeout 300 "$browser" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
  --disable-background-networking --disable-component-update --disable-sync \
  --user-data-dir="$work/profile" --enable-unsafe-swiftshader --use-angle=swiftshader \
  --enable-logging=stderr --v=0 --virtual-time-budget=60000 \
  --dump-dom "file://$page?selftest" >"$work/dom.html" 2>"$work/log.txt"
rc=$?
set -e
echo "chromium: $("$browser" --version 2>/dev/null | head -n 1), exit $rc, $(( $(date +%s) - start )) s"
verdict="$(grep -o 'data-selftest="[a-z]*"' "$work/dom.html" | head -n 1 || true)"
result="$(grep -o "data-selftest-result=\"[^\"]*\"" "$work/dom.html" | head -n 1 | sed 's/&quot;/"/g' || true)"
echo "page self-test: ${verdict:-none} ${result}"
# VIEW_PNG=file keeps the first 3-D view as the page rendered it (to look at).
if [ -n "${VIEW_PNG:-}" ]; then
  grep -o 'data-selftest-image="data:image/png;base64,[^"]*"' "$work/dom.html" | head -n 1 | sed 's/^data-selftest-image="data:image\/png;base64,//; s/"$//' | base64 -d >"$VIEW_PNG" || true
fi
uncaught="$(grep -a 'CONSOLE' "$work/log.txt" | grep -aiE 'uncaught|error' || true)"
if [ -n "$uncaught" ]; then
  echo "console errors:"; echo "$uncaught"
fi
if [ "$verdict" != 'data-selftest="pass"' ] || [ -n "$uncaught" ]; then
  echo "--- chromium log (last 40 lines)"; tail -n 40 "$work/log.txt"
  echo "report.html check: 0 passed, 1 failed"
  exit 1
fi
echo "report.html check: 1 passed, 0 failed"
