#!/usr/bin/env bash
# Fails, with the diff, when schemas/scenario.schema.json is not what the given twinbench's
# `schema` verb writes from the parser's key tables (bench/io/scenario_keys.h): a key added,
# renamed or re-described without regenerating the shipped schema.
# Fix: twinbench schema --out schemas/scenario.schema.json
#   tests/docs/schema_up_to_date_test.sh TWINBENCH
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
BIN="${1:?usage: $0 TWINBENCH}"
TMP="$(mktemp)"
trap 'rm -f "$TMP"' EXIT
"$BIN" schema > "$TMP"
if ! diff -u "$ROOT/schemas/scenario.schema.json" "$TMP"; then
  echo "schemas/scenario.schema.json is stale: run twinbench schema --out" \
       "schemas/scenario.schema.json and commit the result" >&2
  exit 1
fi
echo "schemas/scenario.schema.json matches twinbench schema"
