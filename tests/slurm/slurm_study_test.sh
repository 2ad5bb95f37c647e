#!/usr/bin/env bash
# A real study on a real Slurm cluster: starts scripts/slurm/local_cluster.sh in a temporary
# folder, submits a 4-task job array of scenarios/study_small.yaml (8 trials) with
# scripts/slurm/submit_study.sh --wait and the built twinbench, which merges the shards in its
# dependent job; then runs the same study locally (twinbench study --jobs 2) and checks that
# the merged records equal the local ones: study-merge of the local folder with the four shards
# must find every trial twice and no pair different in what it found (only in how it ran:
# bench/report/trial_record.h), and the merged summary.json must be byte-equal to the local one.
# The cluster is always stopped (trap EXIT) and no daemon or job of it may be left.
#   tests/slurm/slurm_study_test.sh TWINBENCH
# Exit 77 (skipped) when not root or when munge / slurmctld / slurmd / slurm-client are missing.
set -euo pipefail

SRC="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd -P)"
CLUSTER="$SRC/scripts/slurm/local_cluster.sh"
SUBMIT="$SRC/scripts/slurm/submit_study.sh"
SCENARIO="$SRC/scenarios/study_small.yaml"
TRIALS=8 TASKS=4

skip() { echo "SKIP: $*"; exit 77; }
fail() { echo "FAIL: $*" >&2; exit 1; }

[ $# -eq 1 ] || { echo "usage: $0 TWINBENCH" >&2; exit 2; }
[ -x "$1" ] || fail "TWINBENCH=$1 is not an executable"
export TWINBENCH="$(cd "$(dirname "$1")" && pwd -P)/$(basename "$1")"
[ "$(id -u)" -eq 0 ] || skip "needs root (the local cluster runs SlurmUser=root)"
missing=()
for t in munged munge slurmctld slurmd sbatch squeue sinfo scancel ss; do
  command -v "$t" >/dev/null 2>&1 || missing+=("$t")
done
[ ${#missing[@]} -eq 0 ] ||
  skip "not installed: ${missing[*]} (scripts/install_deps.sh installs slurmctld slurmd slurm-client munge)"

# Two free ports (another cluster, e.g. the harness test's, may run on this machine).
in_use() { ss -Htln "sport = :$1" | grep -q .; }
base=47917
while in_use "$base" || in_use $((base + 1)); do
  base=$((base + 10))
  ((base < 48917)) || fail "no free port pair in 47917-48917"
done
export TWIN_SLURMCTLD_PORT=$base TWIN_SLURMD_PORT=$((base + 1))

child=""
run() {
  local rc=0
  "$@" &
  child=$!
  wait "$child" || rc=$?
  child=""
  return $rc
}

DIR="$(mktemp -d /tmp/twin-slurm-study.XXXXXX)"
started=0
exec 3>&1 4>&2
cleanup() {
  local rc=$?
  exec 1>&3 2>&4
  if [ -n "$child" ]; then
    kill "$child" 2>/dev/null || true
    wait "$child" 2>/dev/null || true
  fi
  if [ $started -eq 1 ]; then
    if [ $rc -ne 0 ]; then
      echo "--- logs of the failed run ($DIR)"
      tail -n 30 "$DIR"/log/*.log "$DIR"/study/logs/*.out "$DIR"/study/shard_*/logs/*.log \
        2>/dev/null || true
    fi
    "$CLUSTER" stop "$DIR" || rc=1
  fi
  local left
  left="$(pgrep -a -f "$DIR" || true)"
  # Trial processes name only relative paths; they are found by their working directory.
  for p in /proc/[0-9]*; do
    case "$(readlink "$p/cwd" 2>/dev/null)" in
      "$DIR"*) left="$left ${p#/proc/}:$(tr '\0' ' ' <"$p/cmdline" 2>/dev/null)" ;;
    esac
  done
  left="${left# }"
  if [ -n "$left" ]; then
    echo "FAIL: processes left behind:" >&2
    echo "$left" >&2
    rc=1
  fi
  rm -rf "$DIR"
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT TERM

t0=$SECONDS
started=1
run "$CLUSTER" start "$DIR"
export SLURM_CONF="$DIR/slurm.conf" TWIN_STUDY_POLL_S=1
echo "cluster up in $((SECONDS - t0)) s"

t1=$SECONDS
OUT="$DIR/study"
rc=0
run timeout 600 "$SUBMIT" --wait "$SCENARIO" "$TRIALS" "$TASKS" "$OUT" --cpus-per-task=1 \
  --time=10 >"$DIR/submit.out" 2>&1 || rc=$?
cat "$DIR/submit.out"
[ $rc -eq 0 ] || fail "submit_study.sh --wait exited $rc"
grep -qx "merged=$OUT/merged" "$DIR/submit.out" || fail "no merged= line"
for ((i = 0; i < TASKS; i++)); do
  n="$(wc -l <"$OUT/shard_$i/trials.jsonl")"
  [ "$n" -eq $((TRIALS / TASKS)) ] || fail "shard $i recorded $n trials, want $((TRIALS / TASKS))"
done
[ "$(wc -l <"$OUT/merged/trials.jsonl")" -eq "$TRIALS" ] || fail "merged: not $TRIALS trials"
[ -s "$OUT/merged/summary.html" ] || fail "no merged summary.html"
echo "array of $TASKS shards and the merge job: $((SECONDS - t1)) s"

t1=$SECONDS
run "$TWINBENCH" study "$SCENARIO" --trials "$TRIALS" --jobs 2 --quiet --out "$DIR/local" \
  >"$DIR/local.out" 2>&1 || { cat "$DIR/local.out"; fail "the local study failed"; }
echo "local study of $TRIALS trials: $((SECONDS - t1)) s"
run "$TWINBENCH" study-merge "$DIR/local" "$OUT"/shard_* --out "$DIR/check" >"$DIR/check.out" 2>&1 ||
  { cat "$DIR/check.out"; fail "study-merge of local and shards failed"; }
cat "$DIR/check.out"
if ! grep -q "$TRIALS trials ($TRIALS duplicates dropped, 0 of them different)" "$DIR/check.out"; then
  # Keep the records for a look (the folder itself is removed).
  keep="$(mktemp -d /tmp/twin-slurm-study-failure.XXXXXX)"
  cp -r "$DIR/local" "$OUT" "$keep/" 2>/dev/null || true
  fail "the Slurm shards' records differ from the local study's (records kept in $keep)"
fi
cmp "$DIR/local/summary.json" "$OUT/merged/summary.json" ||
  fail "merged summary.json differs from the local study's"

t1=$SECONDS
"$CLUSTER" stop "$DIR"
started=0
echo "cluster stopped in $((SECONDS - t1)) s; total $((SECONDS - t0)) s"
echo PASS
