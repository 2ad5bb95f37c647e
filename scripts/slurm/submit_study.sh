#!/usr/bin/env bash
# Submits a twinbench Monte Carlo study to Slurm: a job array of TASKS shards
# (study_array.sbatch: task i runs trials i, i+TASKS, ... into OUT/shard_i) and a merge job
# (study_merge.sbatch: OUT/merged) that starts when every task has succeeded
# (--dependency=afterok, --kill-on-invalid-dep=yes: a failed task cancels the merge).
#
#   scripts/slurm/submit_study.sh [--wait] SCENARIO TRIALS TASKS OUT [sbatch options...]
#
# The sbatch options (e.g. --partition=P --cpus-per-task=C --time=HH:MM:SS) go to both jobs;
# --cpus-per-task becomes each shard's --jobs. OUT must be new or empty and on a file system the
# compute nodes share; the jobs' logs go to OUT/logs/. Prints array_job=ID and merge_job=ID.
# With --wait: waits for the jobs (polling squeue; no accounting storage needed), then exits 0
# when every shard and the merge recorded exit status 0 (OUT/shard_i/.exit_code,
# OUT/merged/.exit_code), 1 otherwise, naming the failed shards and their logs.
#
# Environment:
#   TWINBENCH          the twinbench binary (default: build/bin/twinbench of this checkout);
#                      made absolute, it must be visible on the compute nodes
#   TWIN_STUDY_POLL_S  seconds between squeue polls with --wait (default 10)
#   SLURM_CONF         as for any Slurm command (e.g. the local test cluster's slurm.conf)
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)"
REPO="$(cd "$HERE/../.." && pwd -P)"
POLL="${TWIN_STUDY_POLL_S:-10}"

die() { echo "submit_study: error: $*" >&2; exit 2; }
usage() {
  echo "usage: $0 [--wait] SCENARIO TRIALS TASKS OUT [sbatch options...]" >&2
  exit 2
}

WAIT=0
while [ $# -gt 0 ]; do
  case "$1" in
    --wait) WAIT=1; shift ;;
    -h | --help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    --) shift; break ;;
    -*) die "unknown option $1 (sbatch options go after OUT)" ;;
    *) break ;;
  esac
done
[ $# -ge 4 ] || usage
SCENARIO="$1" TRIALS="$2" TASKS="$3" OUT="$4"
shift 4
EXTRA=("$@")

[[ "$TRIALS" =~ ^[1-9][0-9]*$ ]] || die "TRIALS must be a positive integer (got '$TRIALS')"
[[ "$TASKS" =~ ^[1-9][0-9]*$ ]] || die "TASKS must be a positive integer (got '$TASKS')"
((TASKS <= TRIALS)) || die "TASKS ($TASKS) > TRIALS ($TRIALS): some shards would have no trial"
command -v sbatch >/dev/null 2>&1 || die "sbatch not found (install slurm-client)"

# Absolute paths: the jobs run elsewhere.
TWINBENCH="${TWINBENCH:-$REPO/build/bin/twinbench}"
if [[ "$TWINBENCH" != */* ]]; then
  TWINBENCH="$(command -v "$TWINBENCH")" || die "TWINBENCH: '$TWINBENCH' is not on PATH"
fi
if [ ! -f "$TWINBENCH" ] || [ ! -x "$TWINBENCH" ]; then
  die "TWINBENCH=$TWINBENCH is not an executable file (build first, or set TWINBENCH)"
fi
TWINBENCH="$(cd "$(dirname "$TWINBENCH")" && pwd -P)/$(basename "$TWINBENCH")"
if [ -e "$SCENARIO" ]; then
  SCENARIO="$(cd "$(dirname "$SCENARIO")" && pwd -P)/$(basename "$SCENARIO")"
fi
if [ -e "$OUT" ] && [ -n "$(ls -A "$OUT" 2>/dev/null)" ]; then
  die "OUT=$OUT is not empty (shards of another study would be merged); remove it or choose another"
fi
mkdir -p "$OUT/logs"
OUT="$(cd "$OUT" && pwd -P)"
export TWINBENCH SCENARIO TRIALS TASKS OUT

jobid() { local id="$1"; echo "${id%%;*}"; } # --parsable prints ID or ID;CLUSTER

array_job="$(sbatch --parsable --export=ALL --array="0-$((TASKS - 1))" \
  --output="$OUT/logs/shard_%a.out" "${EXTRA[@]}" "$HERE/study_array.sbatch")" ||
  die "sbatch of the job array failed"
array_job="$(jobid "$array_job")"
merge_job="$(sbatch --parsable --export=ALL --dependency="afterok:$array_job" \
  --kill-on-invalid-dep=yes --output="$OUT/logs/merge.out" "${EXTRA[@]}" \
  "$HERE/study_merge.sbatch")" || {
  scancel "$array_job" 2>/dev/null || true
  die "sbatch of the merge job failed (cancelled array job $array_job)"
}
merge_job="$(jobid "$merge_job")"
echo "array_job=$array_job"
echo "merge_job=$merge_job"
[ $WAIT -eq 1 ] || exit 0

# 0 while the job (any task of an array) is pending, running or completing; 1 once it has left
# the queue (squeue drops finished jobs; after MinJobAge it answers "Invalid job id").
squeue_errors=0
queued() {
  local out
  if out="$(squeue -h -j "$1" -o %i 2>&1)"; then
    squeue_errors=0
    [ -n "$out" ]
    return
  fi
  case "$out" in *"Invalid job id"*) return 1 ;; esac
  squeue_errors=$((squeue_errors + 1))
  ((squeue_errors < 10)) || die "squeue keeps failing: $out"
  return 0
}

while queued "$array_job"; do sleep "$POLL"; done
failed=()
for ((i = 0; i < TASKS; i++)); do
  code="$(cat "$OUT/shard_$i/.exit_code" 2>/dev/null || echo none)"
  [ "$code" = 0 ] || failed+=("$i:$code")
done
if [ ${#failed[@]} -gt 0 ]; then
  scancel "$merge_job" 2>/dev/null || true
  echo "submit_study: ${#failed[@]} of $TASKS shards failed (shard:exit status; none = killed" \
    "or never ran); merge job $merge_job cancelled:" >&2
  for f in "${failed[@]}"; do
    echo "  shard ${f%%:*}: ${f#*:}  log: $OUT/logs/shard_${f%%:*}.out" >&2
  done
  exit 1
fi
while queued "$merge_job"; do sleep "$POLL"; done
code="$(cat "$OUT/merged/.exit_code" 2>/dev/null || echo none)"
if [ "$code" != 0 ]; then
  echo "submit_study: merge job $merge_job failed (exit status $code); log: $OUT/logs/merge.out" >&2
  exit 1
fi
echo "merged=$OUT/merged"
