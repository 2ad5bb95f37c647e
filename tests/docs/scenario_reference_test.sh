#!/usr/bin/env bash
# Fails, with the diff, when docs/reference/scenario.md is not what scripts/scenario_reference.sh
# writes from the documentation comments at the top of the scenario parser's headers (a key
# added, renamed or re-described in bench/ without regenerating the reference).
# Fix: scripts/scenario_reference.sh
#   tests/docs/scenario_reference_test.sh
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
TMP="$(mktemp)"
trap 'rm -f "$TMP"' EXIT
"$ROOT/scripts/scenario_reference.sh" "$TMP"
if ! diff -u "$ROOT/docs/reference/scenario.md" "$TMP"; then
  echo "docs/reference/scenario.md is stale: run scripts/scenario_reference.sh and commit the result" >&2
  exit 1
fi
echo "docs/reference/scenario.md matches the scenario parser's headers"
