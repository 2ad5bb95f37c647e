#!/usr/bin/env bash
# The identification benchmark (the engine: docs/explanation/architecture.md): `twinbench identify` on synthetic
# optical-axis measurement files of ROWS rows each (default 5000 and 20000; 5 axes, the true
# geometry and the noise drawn by `twinbench synthesize-measurements`), printing the wall time
# and the peak resident memory of each run (GNU time's %e and %M).
#   scripts/benchmark_identify.sh [ROWS ...]        (TWINBENCH=... for another binary)
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
TB="${TWINBENCH:-$REPO/build/bin/twinbench}"
MODEL="$REPO/models/reinovo_r2.yaml"
[ -x "$TB" ] || { echo "error: $TB: not built (scripts/build.sh)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "error: /usr/bin/time: missing (Debian package 'time')" >&2; exit 2; }
[ $# -gt 0 ] || set -- 5000 20000
D="$(mktemp -d /tmp/twin-benchmark-identify.XXXXXX)"
trap 'rm -rf "$D"' EXIT

echo "benchmark: $(nproc) CPUs, load average $(cut -d' ' -f1-3 /proc/loadavg) at the start"
printf '%8s %10s %12s  %s\n' rows "wall [s]" "peak [MB]" "identify's result"
for rows in "$@"; do
  [[ "$rows" =~ ^[1-9][0-9]*$ ]] || { echo "error: ROWS: expected a positive integer, got '$rows'" >&2; exit 2; }
  "$TB" synthesize-measurements --model "$MODEL" --rows "$rows" --seed 3 \
    --out "$D/m$rows.csv" >/dev/null
  /usr/bin/time -f '%e %M' -o "$D/time$rows" \
    "$TB" identify --model "$MODEL" --measurements "$D/m$rows.csv" --out "$D/out$rows" \
    >"$D/log$rows" 2>&1 || { cat "$D/log$rows"; exit 1; }
  read -r wall kb <"$D/time$rows"
  summary="$(grep -m1 'misaligned error' "$D/log$rows" || true)"
  printf '%8d %10.2f %12.1f  %s\n' "$rows" "$wall" "$(awk "BEGIN { print $kb / 1024 }")" "$summary"
done
echo "load average $(cut -d' ' -f1-3 /proc/loadavg) at the end"
