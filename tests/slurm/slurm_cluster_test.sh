#!/usr/bin/env bash
# The Slurm harness on a real one-node cluster: starts scripts/slurm/local_cluster.sh in a
# temporary folder, submits a 4-shard study of 10 trials with scripts/slurm/submit_study.sh
# --wait using tests/slurm/fake_twinbench.sh as TWINBENCH, checks that the merged output has
# every trial exactly once and that each shard ran its own trials; then a study whose shard 2
# fails must make submit_study.sh --wait exit 1 and cancel the merge. The cluster is always
# stopped (trap EXIT) and no daemon of it may be left.
# Exit 77 (skipped) when not root or when munge / slurmctld / slurmd / slurm-client are missing.
set -euo pipefail

SRC="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd -P)"
CLUSTER="$SRC/scripts/slurm/local_cluster.sh"
SUBMIT="$SRC/scripts/slurm/submit_study.sh"

skip() { echo "SKIP: $*"; exit 77; }
fail() { echo "FAIL: $*" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || skip "needs root (the local cluster runs SlurmUser=root)"
missing=()
for t in munged munge slurmctld slurmd sbatch squeue sinfo scancel ss; do
  command -v "$t" >/dev/null 2>&1 || missing+=("$t")
done
[ ${#missing[@]} -eq 0 ] ||
  skip "not installed: ${missing[*]} (scripts/install_deps.sh installs slurmctld slurmd slurm-client munge)"

# Two free ports (another cluster may run on this machine).
in_use() { ss -Htln "sport = :$1" | grep -q .; }
base=47817
while in_use "$base" || in_use $((base + 1)); do
  base=$((base + 10))
  ((base < 48817)) || fail "no free port pair in 47817-48817"
done
export TWIN_SLURMCTLD_PORT=$base TWIN_SLURMD_PORT=$((base + 1))

# Runs a command in the background and waits for it, so that a signal to this script runs the
# cleanup at once (bash defers traps while a foreground command runs).
child=""
run() {
  local rc=0
  "$@" &
  child=$!
  wait "$child" || rc=$?
  child=""
  return $rc
}

DIR="$(mktemp -d /tmp/twin-slurm-test.XXXXXX)"
started=0
exec 3>&1 4>&2 # the test's own stdout and stderr, for the cleanup
cleanup() {
  local rc=$?
  exec 1>&3 2>&4 # a signal may come while run's output goes to a file
  if [ -n "$child" ]; then
    kill "$child" 2>/dev/null || true
    wait "$child" 2>/dev/null || true
  fi
  if [ $started -eq 1 ]; then
    if [ $rc -ne 0 ]; then
      echo "--- logs of the failed run ($DIR)"
      tail -n 20 "$DIR"/log/*.log "$DIR"/study*/logs/*.out 2>/dev/null || true
    fi
    "$CLUSTER" stop "$DIR" || rc=1
  fi
  # Nothing of this cluster may be left (its processes name $DIR on their command line).
  local left
  left="$(pgrep -a -f "$DIR" || true)"
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
"$CLUSTER" status "$DIR" >/dev/null || fail "status after start"
export SLURM_CONF="$DIR/slurm.conf"
echo "cluster up in $((SECONDS - t0)) s"

export TWINBENCH="$SRC/tests/slurm/fake_twinbench.sh" TWIN_STUDY_POLL_S=1
SCENARIO="$SRC/scenarios/twin_demo.yaml"
TRIALS=10 TASKS=4

# A study that succeeds.
t1=$SECONDS
OUT="$DIR/study"
rc=0
run timeout 90 "$SUBMIT" --wait "$SCENARIO" "$TRIALS" "$TASKS" "$OUT" --time=5 --cpus-per-task=1 \
  >"$DIR/submit.out" || rc=$?
cat "$DIR/submit.out"
[ $rc -eq 0 ] || fail "submit_study.sh --wait exited $rc"
grep -qx "merged=$OUT/merged" "$DIR/submit.out" || fail "no merged= line"
merged="$OUT/merged/trials.jsonl"
[ -f "$merged" ] || fail "no $merged"
got="$(sed -n 's/^{"trial": \([0-9]*\),.*/\1/p' "$merged" | sort -n | tr '\n' ' ')"
want="$(seq 0 $((TRIALS - 1)) | tr '\n' ' ')"
[ "$got" = "$want" ] || fail "merged trials: got '$got', want '$want' (each exactly once)"
[ "$(wc -l <"$merged")" -eq "$TRIALS" ] || fail "$merged has $(wc -l <"$merged") lines, want $TRIALS"
for ((i = 0; i < TASKS; i++)); do
  f="$OUT/shard_$i/trials.jsonl"
  [ "$(cat "$OUT/shard_$i/.exit_code")" = 0 ] || fail "shard $i exit code"
  want_i="$(seq "$i" "$TASKS" $((TRIALS - 1)) | tr '\n' ' ')"
  got_i="$(sed -n "s|^{\"trial\": \([0-9]*\), \"shard\": \"$i/$TASKS\", \"jobs\": 1, \"scenario\": \"$SCENARIO\"}\$|\1|p" "$f" | tr '\n' ' ')"
  [ "$got_i" = "$want_i" ] || fail "shard $i: trials '$got_i', want '$want_i' ($(cat "$f"))"
done
[ "$(cat "$OUT/merged/.exit_code")" = 0 ] || fail "merge exit code"
echo "study of $TRIALS trials in $TASKS shards merged in $((SECONDS - t1)) s"

# A study whose shard 2 fails: --wait exits 1 and the merge job does not run.
t1=$SECONDS
OUT2="$DIR/study_fail"
rc=0
FAKE_TWINBENCH_FAIL_SHARD=2 run timeout 90 "$SUBMIT" --wait "$SCENARIO" "$TRIALS" "$TASKS" "$OUT2" \
  --time=5 >"$DIR/submit_fail.out" 2>&1 || rc=$?
cat "$DIR/submit_fail.out"
[ $rc -eq 1 ] || fail "submit_study.sh --wait with a failing shard exited $rc, want 1"
grep -q "shard 2: 3 " "$DIR/submit_fail.out" || fail "the failed shard 2 (exit 3) is not named"
[ ! -e "$OUT2/merged" ] || fail "the merge ran although shard 2 failed"
merge2="$(sed -n 's/^merge_job=//p' "$DIR/submit_fail.out")"
for ((k = 0; k < 20; k++)); do
  [ -z "$(squeue -h -j "$merge2" -o %i 2>/dev/null)" ] && break
  sleep 0.5
done
[ -z "$(squeue -h -j "$merge2" -o %i 2>/dev/null)" ] || fail "merge job $merge2 still queued"
echo "failing study reported in $((SECONDS - t1)) s"

t1=$SECONDS
"$CLUSTER" stop "$DIR"
started=0
echo "cluster stopped in $((SECONDS - t1)) s; total $((SECONDS - t0)) s"
echo PASS
