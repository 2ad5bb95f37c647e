#!/usr/bin/env bash
# The speed of trials against issue 42's targets, written to docs/results/study_speed.md with
# the date, commit, machine, load and commands: `twinbench benchmark-twin` on the paper
# scenario (what a frame and a move cost) and scripts/benchmark_study.sh (a paper run with
# planning, then a study of the same scenario with the plan cached, --jobs 1 and --jobs 2).
# Run it on an idle machine: other work shows in every figure (the load average is printed).
#   scripts/study_speed_table.sh [TRIALS]   (even, default 6; TWINBENCH=... for another build)
set -euo pipefail
cd "$(dirname "$0")/.."
tb="${TWINBENCH:-build/bin/twinbench}"
trials="${1:-6}"
[ -x "$tb" ] || { echo "error: $tb: not built (scripts/build.sh)" >&2; exit 2; }
[[ "$trials" =~ ^[1-9][0-9]*$ ]] && [ $((trials % 2)) -eq 0 ] ||
  { echo "error: TRIALS: expected a positive even integer, got '$trials'" >&2; exit 2; }
tb="$(cd "$(dirname "$tb")" && pwd -P)/$(basename "$tb")"
out=docs/results/study_speed.md
twin_log="$(mktemp)" study_log="$(mktemp)" tmp="$(mktemp)"
trap 'rm -f "$twin_log" "$study_log" "$tmp"' EXIT
load_before="$(cut -d' ' -f1-3 /proc/loadavg)"
"$tb" benchmark-twin scenarios/paper_reinovo.yaml >"$twin_log" 2>&1
TWINBENCH="$tb" scripts/benchmark_study.sh "$trials" >"$study_log" 2>&1 ||
  { cat "$study_log" >&2; exit 1; }

# The figures the targets name, from benchmark_study.sh's lines.
run_wall="$(sed -n 's/.*wall time of the process: \([0-9.]*\) s.*/\1/p' "$study_log")"
trial_1="$(sed -n 's/.*--jobs 1:.*mean trial wall time \([0-9.]*\) s.*/\1/p' "$study_log")"
ratio="$(sed -n 's/.*trial rate: \([0-9.]*\).*/\1/p' "$study_log")"
verdict() { awk -v v="$1" -v t="$2" -v op="$3" 'BEGIN {
  if (v == "") { print "not measured"; exit }
  print ((op == "le" ? v <= t : v >= t) ? "met" : "not met") }'; }
{
  echo "# Speed of trials (issue 42's targets)"
  echo
  echo "Written by \`scripts/study_speed_table.sh $trials\` on $(date -u '+%Y-%m-%d %H:%M UTC') at commit"
  echo "$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- calib sim bench || echo ' (with uncommitted changes)') ($("$tb" --version)), on $(uname -m), $(nproc) cores,"
  echo "$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo) GiB, OSMesa (llvmpipe); load average $load_before at the start."
  echo
  echo "| target | measured | |"
  echo "|---|---|---|"
  echo "| a paper-scenario run, planning included: at most 20 s | ${run_wall:-?} s | $(verdict "$run_wall" 20 le) |"
  echo "| a cached study trial (\`--jobs 1\`): at most 8 s | ${trial_1:-?} s | $(verdict "$trial_1" 8 le) |"
  echo "| \`--jobs 2\` / \`--jobs 1\` trial rate: at least 1.8 | ${ratio:-?} | $(verdict "$ratio" 1.8 ge) |"
  echo
  echo "The run's \`timing\` line splits its wall time into stages (planning runs in the"
  echo "background, beside the intrinsics; \`waiting for the plans\` is what is left of it);"
  echo "\`cell\` is the time spent in the twin's frames and moves."
  echo
  echo "    scripts/benchmark_study.sh $trials"
  echo
  sed 's/^/    /; s/folder \/tmp\/[^ ]*/folder (a temporary folder)/' "$study_log"
  echo
  echo "    twinbench benchmark-twin scenarios/paper_reinovo.yaml"
  echo
  sed 's/^/    /' "$twin_log"
} >"$tmp"
mv "$tmp" "$out"
echo "wrote $out" >&2
