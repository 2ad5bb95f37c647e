#!/usr/bin/env bash
# Issue 43: JSON appears only in bench/report/, where one file per report or file format knows
# its keys. Lists every source file of calib/, sim/ and bench/ outside bench/report/ that uses
# nlohmann::json (includes it, names it, or declares a json alias); exits 1 if there is one.
# Usage: scripts/json_outside_report.sh   (from anywhere; checks this checkout)
set -euo pipefail
cd "$(dirname "$0")/.."
found=$(grep -rlE 'nlohmann|json\.hpp|using json *=' --include='*.cc' --include='*.h' \
          calib sim bench | grep -v '^bench/report/' || true)
if [[ -n "$found" ]]; then
  echo "JSON outside bench/report/ (move the keys into a bench/report/ file):"
  echo "$found" | sed 's/^/  /'
  exit 1
fi
echo "JSON only in bench/report/"
