#!/usr/bin/env bash
# Times CI as it runs on a submission: `bash .ci/run` in a clean clone of this repository's HEAD
# (with ../shared beside it, as CI lays it), and appends the result to docs/results/ci_time.md
# with the date, commit, machine and command. The clone is removed afterwards; ccache's cache
# (outside the clone) is kept, and its hit rate for the run is recorded, since a warm cache is
# what CI on a developer's machine meets.
#   scripts/ci_time.sh [LOG]      LOG: where .ci/run's output goes (default: a temporary file)
set -euo pipefail
cd "$(dirname "$0")/.."
top="$PWD"
commit="$(git rev-parse --short HEAD)"
[ -d ../shared ] || { echo "error: ../shared: not found beside the repository (CI lays it there)" >&2; exit 2; }
work="$(mktemp -d /tmp/twinbench-ci-time.XXXXXX)"
log="${1:-$work.log}"
trap 'rm -rf "$work"' EXIT
cp -r ../shared "$work/shared"
git clone -q "$top" "$work/main"
stats_before="$(ccache --print-stats 2>/dev/null | grep -E '^(direct_cache_hit|preprocessed_cache_hit|cache_miss)\s' || true)"
start=$(date +%s)
status=0
(cd "$work/main" && CI=true bash .ci/run </dev/null) >"$log" 2>&1 || status=$?
seconds=$(( $(date +%s) - start ))
stats_after="$(ccache --print-stats 2>/dev/null | grep -E '^(direct_cache_hit|preprocessed_cache_hit|cache_miss)\s' || true)"
delta() {  # the counter's growth during the run
  local before after
  before=$(echo "$stats_before" | awk -v k="$1" '$1 == k {print $2}')
  after=$(echo "$stats_after" | awk -v k="$1" '$1 == k {print $2}')
  echo $(( ${after:-0} - ${before:-0} ))
}
hits=$(( $(delta direct_cache_hit) + $(delta preprocessed_cache_hit) ))
misses=$(delta cache_miss)
tests="$(grep -E 'tests passed|tests failed' "$log" | tail -1)"
file=docs/results/ci_time.md
if [ ! -f "$file" ]; then
  cat >"$file" <<'HEAD'
# Clean-clone CI time

Written by `scripts/ci_time.sh`: `bash .ci/run` in a fresh clone of the commit, as CI runs it
(install check, Release build, every test with `ctest -j 2`, the sanitizer job). A row per run;
nobody edits them by hand.

| date (UTC) | commit | machine | exit | wall time | ccache hits / misses | tests |
|---|---|---|---|---|---|---|
HEAD
fi
printf '| %s | %s | %s, %s cores, %s GiB | %s | %d min %02d s | %s / %s | %s |\n' \
  "$(date -u '+%Y-%m-%d %H:%M')" "$commit" "$(uname -m)" "$(nproc)" \
  "$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo)" "$status" \
  $((seconds / 60)) $((seconds % 60)) "$hits" "$misses" "${tests:-no ctest summary}" >>"$file"
echo "ci_time: exit $status in ${seconds} s (ccache $hits hits, $misses misses); row added to $file; log $log"
exit "$status"
