#!/usr/bin/env bash
# The calibration report as a browser sees it: simulate a small
# dataset, calibrate it with the real fgcal command (which writes the report
# beside the output), open the page in headless Chromium and check that
#  - every plot's <svg id=...> is in the rendered DOM,
#  - the browser logged no console message (the page has no script, so any is
#    an error), checked to be detectable on a page that does log one,
#  - the page loads nothing from the network (no remote src/href/url(), no
#    script or stylesheet link) and every image it shows is a PNG beside it.
# Usage: test_report_render.sh PATH_TO_FGCAL
# Exit 77 (ctest: skipped) when chromium is missing, unless
# FGCAL_REQUIRE_CHROMIUM=1 (set by scripts/quickstart.sh test, which installs it).
set -euo pipefail
fgcal="$1"

chromium_bin="$(command -v chromium || command -v chromium-browser || true)"
if [ -z "$chromium_bin" ]; then
  if [ "${FGCAL_REQUIRE_CHROMIUM:-0}" = "1" ]; then
    echo "FAIL: chromium is required (FGCAL_REQUIRE_CHROMIUM=1) but not installed: apt-get install chromium" >&2
    exit 1
  fi
  echo "SKIPPED: chromium is not installed (apt-get install chromium; 'bash scripts/quickstart.sh test' installs it)"
  exit 77
fi

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# Renders $1 (a file path); DOM to $2, browser log to $3.
render() {
  HOME="$work" timeout 180 "$chromium_bin" --headless=new --no-sandbox --disable-gpu --no-first-run \
    --user-data-dir="$work/profile" --enable-logging=stderr --v=0 --dump-dom "file://$1" >"$2" 2>"$3" ||
    fail "chromium failed on $1 (log: $(tail -5 "$3"))"
}
console_messages() { grep -E ':CONSOLE[:(]' "$1" || true; }

# The console check must be able to see an error: a page that logs one.
printf '<!DOCTYPE html><html><body><script>console.error("probe")</script></body></html>\n' >"$work/probe.html"
render "$work/probe.html" "$work/probe.dom" "$work/probe.log"
console_messages "$work/probe.log" | grep -q probe ||
  fail "cannot see console messages in chromium's log: $(tail -5 "$work/probe.log")"

"$fgcal" simulate --out "$work/ds" --frames 30 --seed 3 >"$work/simulate.log" 2>&1 ||
  fail "fgcal simulate: $(cat "$work/simulate.log")"
"$fgcal" calibrate "$work/ds" -o "$work/cal.yaml" --threads 2 >"$work/calibrate.log" 2>&1 ||
  fail "fgcal calibrate: $(cat "$work/calibrate.log")"
page="$work/cal_report/index.html"
[ -s "$page" ] || fail "no report at $page; calibrate said: $(cat "$work/calibrate.log")"
grep -q "report: $page" "$work/calibrate.log" || fail "calibrate does not say where the report is"

# Self-contained.
if grep -Eio '(src|href)[[:space:]]*=[[:space:]]*["'\'']?[[:space:]]*(https?:|//)[^" >]*' "$page"; then
  fail "the page loads a network resource"
fi
if grep -Eiq 'url\([[:space:]]*["'\'']?[[:space:]]*(https?:|//)' "$page"; then fail "the page's CSS loads a network resource"; fi
if grep -Eiq '<script|<link|@import' "$page"; then fail "the page has a script or a stylesheet link"; fi
images=0
while IFS= read -r src; do
  file="$work/cal_report/$src"
  [ -s "$file" ] || fail "image $src is missing"
  [ "$(head -c 4 "$file" | tail -c 3)" = "PNG" ] || fail "image $src is not a PNG"
  images=$((images + 1))
done < <(grep -o '<img src="[^"]*"' "$page" | sed 's/<img src="//; s/"$//')
[ "$images" -ge 6 ] || fail "expected at least 3 overlay images per camera, found $images"

# Rendered: every plot, no console message.
render "$page" "$work/dom.html" "$work/chromium.log"
plots=0
for id in rig-top rig-side rig-front convergence \
          coverage-0 reprojection-scatter-0 reprojection-histogram-0 residuals-time-0 \
          coverage-1 reprojection-scatter-1 reprojection-histogram-1 residuals-time-1; do
  grep -q "<svg id=\"$id\"" "$work/dom.html" || fail "plot $id is not in the rendered page"
  plots=$((plots + 1))
done
for section in warnings results rig convergence-section camera-0 camera-1 summary; do
  grep -q "id=\"$section\"" "$work/dom.html" || fail "section $section is not in the rendered page"
done
messages="$(console_messages "$work/chromium.log")"
[ -z "$messages" ] || fail "console messages while rendering the report: $messages"

echo "report renders in $("$chromium_bin" --version 2>/dev/null | head -1): $plots plots, $images images, no console message"
