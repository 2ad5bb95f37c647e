#!/usr/bin/env bash
# The picture of report.html in README.md: runs `twinbench run` on the small shipped scenario
# scenarios/study_small.yaml into a temporary folder and takes a screenshot of the report.html
# it wrote with headless Chromium (Debian package `chromium`), into docs/images/report.png.
#   scripts/report_screenshot.sh [OUT_PNG]      (TWINBENCH=... for another binary)
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BIN="${TWINBENCH:-$ROOT/build/bin/twinbench}"
PNG="${1:-$ROOT/docs/images/report.png}"
CHROMIUM="$(command -v chromium || command -v chromium-browser || true)"
if [ -z "$CHROMIUM" ]; then
  echo "error: chromium not found (apt-get install chromium)" >&2
  exit 2
fi
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
cd "$ROOT"
"$BIN" run scenarios/study_small.yaml --out "$TMP/run" > "$TMP/run.log"
mkdir -p "$(dirname "$PNG")"
"$CHROMIUM" --headless --no-sandbox --disable-gpu --hide-scrollbars \
  --user-data-dir="$TMP/profile" --window-size=1200,1500 \
  --screenshot="$PNG" "file://$TMP/run/report.html" 2> "$TMP/chromium.log"
echo "wrote $PNG from report.html of scenarios/study_small.yaml"
