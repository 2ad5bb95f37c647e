#!/usr/bin/env bash
# The speed of study trials (docs/explanation/studies.md, "Speed of trials"), measured
# on this machine with the built twinbench:
#   1. one run of scenarios/paper_reinovo.yaml, planning included (its timing line, frames per
#      aligned pose); it also fills a plan cache;
#   2. a study of the same scenario with that plan cached (planning.seed pins the plan): TRIALS
#      trials with --jobs 1, then the same TRIALS with --jobs 2: wall time per trial and trials
#      per minute, and the ratio of the two rates. TRIALS is even, so that --jobs 2 runs full
#      pairs to the end: with an odd count the last trial runs alone and the ratio measures that
#      tail (5 trials: at most 5 / 3 = 1.67 however well two processes share the machine).
#   scripts/benchmark_study.sh [TRIALS]        (default 6; TWINBENCH=... for another binary)
# Prints the figures; keeps its folder (printed) for a look at the reports.
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
TB="${TWINBENCH:-$REPO/build/bin/twinbench}"
TRIALS="${1:-6}"
SCENARIO="$REPO/scenarios/paper_reinovo.yaml"
[ -x "$TB" ] || { echo "error: $TB: not built (scripts/build.sh)" >&2; exit 2; }
[[ "$TRIALS" =~ ^[1-9][0-9]*$ ]] && [ $((TRIALS % 2)) -eq 0 ] ||
  { echo "error: TRIALS: expected a positive even integer, got '$TRIALS'" >&2; exit 2; }
D="$(mktemp -d /tmp/twin-benchmark-study.XXXXXX)"
now() { date +%s.%N; }
calc() { awk "BEGIN { print $1 }"; }

echo "benchmark: $(nproc) CPUs, load average $(cut -d' ' -f1-3 /proc/loadavg) at the start"
echo "1. one paper-scenario run (planning included):"
t0=$(now)
"$TB" run "$SCENARIO" --out "$D/run" --plan-cache "$D/plans" >"$D/run.log" 2>&1
t1=$(now)
grep -E "^timing|^cell|frames/pose" "$D/run.log" | sed 's/^/   /'
printf '   wall time of the process: %.1f s\n' "$(calc "$t1 - $t0")"

for jobs in 1 2; do
  out="$D/study_jobs$jobs"
  # Trials 0..TRIALS-1; every one reads the plan the run above cached.
  t0=$(now)
  "$TB" study "$SCENARIO" --trials "$TRIALS" --shard 0/1 --jobs "$jobs" --quiet \
    --plan-cache "$D/plans" --out "$out" >"$out.log" 2>&1 || { cat "$out.log"; exit 1; }
  t1=$(now)
  wall="$(calc "$t1 - $t0")"
  n="$(wc -l <"$out/trials.jsonl")"
  rate="$(calc "60 * $n / $wall")"
  eval "rate_$jobs=$rate"
  printf '2. study, --jobs %d: %d trials in %.1f s: %.2f trials/min; ' "$jobs" "$n" "$wall" "$rate"
  grep -o "mean trial wall time [0-9.]* s" "$out.log" || echo
done
printf '   --jobs 2 / --jobs 1 trial rate: %.2f\n' "$(calc "$rate_2 / $rate_1")"
echo "   load average $(cut -d' ' -f1-3 /proc/loadavg) at the end; folder $D"
