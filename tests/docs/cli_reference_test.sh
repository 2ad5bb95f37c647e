#!/usr/bin/env bash
# Fails, with the diff, when docs/reference/cli.md is not what scripts/cli_reference.sh writes
# from the given twinbench's --help texts (an option added, renamed or re-described without
# regenerating the reference). Fix: scripts/cli_reference.sh
#   tests/docs/cli_reference_test.sh TWINBENCH
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
BIN="${1:?usage: $0 TWINBENCH}"
TMP="$(mktemp)"
trap 'rm -f "$TMP"' EXIT
TWINBENCH="$BIN" "$ROOT/scripts/cli_reference.sh" "$TMP"
if ! diff -u "$ROOT/docs/reference/cli.md" "$TMP"; then
  echo "docs/reference/cli.md is stale: run scripts/cli_reference.sh and commit the result" >&2
  exit 1
fi
echo "docs/reference/cli.md matches twinbench --help"
