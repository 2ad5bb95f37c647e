#!/usr/bin/env bash
# The GL back ends side by side (sim/render/gl_context.h), written to
# docs/results/render_backends.md with the date, commit, machine and commands: for each of
# TWINBENCH_GL=osmesa and =egl, `twinbench benchmark-twin` on the scenario (twice, the back
# ends alternating, so the table shows the machine's scatter beside the difference) and one cached run
# of it (its plans made beforehand, not timed), and rendering's share of that run: the run's
# timing_s.cell.grab_image over timing_s.total (issue 42: at most 10 % on a GPU machine).
# Where EGL renders on Mesa's software device (no GPU), its figures are llvmpipe's through EGL
# and the 10 % target is not measured. Run it on an idle machine.
#   scripts/render_backends_table.sh [SCENARIO] [OUT]
#   (defaults scenarios/paper_reinovo.yaml, docs/results/render_backends.md; TWINBENCH=... for
#   another build)
set -euo pipefail
cd "$(dirname "$0")/.."
tb="${TWINBENCH:-build/bin/twinbench}"
scenario="${1:-scenarios/paper_reinovo.yaml}"
out="${2:-docs/results/render_backends.md}"
[ -x "$tb" ] || { echo "error: $tb: not built (scripts/build.sh)" >&2; exit 2; }
[ -f "$scenario" ] || { echo "error: $scenario: no such scenario" >&2; exit 2; }
command -v jq >/dev/null || { echo "error: jq is needed (scripts/install_deps.sh)" >&2; exit 2; }
tb="$(cd "$(dirname "$tb")" && pwd -P)/$(basename "$tb")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
load_before="$(cut -d' ' -f1-3 /proc/loadavg)"
gpus="none"
if command -v nvidia-smi >/dev/null && nvidia-smi -L >/dev/null 2>&1; then
  gpus="$(nvidia-smi -L | sed 's/ (UUID.*//' | paste -sd ';' -)"
fi

echo "planning once into the plan cache (not timed)" >&2
TWINBENCH_GL=osmesa "$tb" run "$scenario" --out "$work/warm" --plan-cache "$work/plans" --quiet \
  --no-images >"$work/warm.log" 2>&1 || true
[ -d "$work/plans" ] || { cat "$work/warm.log" >&2; exit 1; }

backends=()
for gl in osmesa egl; do
  echo "TWINBENCH_GL=$gl: benchmark-twin, then a cached run" >&2
  if ! TWINBENCH_GL=$gl "$tb" benchmark-twin "$scenario" >"$work/bench_$gl.log" 2>&1; then
    echo "TWINBENCH_GL=$gl cannot render here: $(tail -1 "$work/bench_$gl.log")" >&2
    continue
  fi
  rc=0
  TWINBENCH_GL=$gl "$tb" run "$scenario" --out "$work/run_$gl" --plan-cache "$work/plans" \
    --quiet --no-images >"$work/run_$gl.log" 2>&1 || rc=$?
  [ "$rc" = 0 ] || [ "$rc" = 3 ] || { cat "$work/run_$gl.log" >&2; exit 1; }  # 3: criteria missed
  backends+=("$gl")
done

# The second round of benchmark-twin, the back ends alternating again.
for gl in "${backends[@]}"; do
  echo "TWINBENCH_GL=$gl: benchmark-twin again" >&2
  TWINBENCH_GL=$gl "$tb" benchmark-twin "$scenario" >"$work/bench2_$gl.log" 2>&1 ||
    { cat "$work/bench2_$gl.log" >&2; exit 1; }
done

frame_ms() { sed -n 's/.*GrabImage (render.*: *\([0-9.]*\) ms\/frame/\1/p' "$1"; }
region_ms() { sed -n 's/.*GrabImageRegion, [0-9]*x[0-9]* centred region: *\([0-9.]*\) ms\/frame/\1/p' "$1"; }

row() {  # row GL: one table row from the benchmark's logs and the run's report.json
  local gl=$1 log="$work/bench_$1.log" report="$work/run_$1/report.json"
  local renderer grab region total grab_s frames share
  renderer="$(sed -n 's/^  GL back end: //p' "$log")"
  grab="$(frame_ms "$log"), $(frame_ms "$work/bench2_$gl.log")"
  region="$(region_ms "$log"), $(region_ms "$work/bench2_$gl.log")"
  total="$(jq '.timing_s.total' "$report")"
  grab_s="$(jq '.timing_s.cell.grab_image' "$report")"
  frames="$(jq '.timing_s.cell.frames' "$report")"
  share="$(awk -v g="$grab_s" -v t="$total" 'BEGIN { printf "%.1f", 100 * g / t }')"
  printf '| %s | %s | %s | %s | %.1f | %s in %.1f s | %s %% |\n' "$gl" "$renderer" "$grab" \
    "$region" "$total" "$frames" "$grab_s" "$share"
}

verdict="not measured: EGL renders on no GPU here"
for gl in "${backends[@]}"; do
  [ "$gl" = egl ] || continue
  if ! grep -q "GL back end: egl (llvmpipe" "$work/bench_egl.log"; then
    share="$(jq -r '100 * .timing_s.cell.grab_image / .timing_s.total' "$work/run_egl/report.json")"
    verdict="$(awk -v s="$share" 'BEGIN { printf "%.1f %%: %s", s, (s <= 10 ? "met" : "not met") }')"
  fi
done

tmp="$(mktemp)"
{
  echo "# Rendering back ends: OSMesa and EGL"
  echo
  echo "Written by \`scripts/render_backends_table.sh $scenario\` on $(date -u '+%Y-%m-%d %H:%M UTC') at commit"
  echo "$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- calib sim bench || echo ' (with uncommitted changes)') ($("$tb" --version)), on $(uname -m), $(nproc) cores,"
  echo "$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo) GiB, GPUs: $gpus; load average $load_before at the start."
  echo
  echo "Each back end in its own processes (\`TWINBENCH_GL=...\`). The frame times are"
  echo "\`twinbench benchmark-twin\`'s, two rounds with the back ends alternating (their spread is"
  echo "this machine's scatter); the run is one \`twinbench run --plan-cache\` of the scenario"
  echo "with its plans made beforehand (a cached study trial's work), and rendering's share is its"
  echo "\`timing_s.cell.grab_image\` over \`timing_s.total\`."
  echo
  echo "| TWINBENCH_GL | renderer | frame [ms], two rounds | board region [ms], two rounds | cached run [s] | frames rendered | rendering's share |"
  echo "|---|---|---|---|---|---|---|"
  for gl in "${backends[@]}"; do row "$gl"; done
  echo
  echo "Issue 42's target, rendering at most 10 % of a trial on a GPU machine: $verdict."
  for gl in "${backends[@]}"; do
    echo
    echo "    TWINBENCH_GL=$gl twinbench benchmark-twin $scenario"
    echo
    sed 's/^/    /' "$work/bench_$gl.log"
  done
} >"$tmp"
mkdir -p "$(dirname "$out")"
mv "$tmp" "$out"
echo "wrote $out" >&2
