#!/usr/bin/env bash
# Stand-in for the twinbench binary's study verbs, for testing the Slurm harness without a build:
#   fake_twinbench.sh study SCENARIO --trials T --shard I/N --jobs J --out D
#     writes D/trials.jsonl: one line {"trial": t, "shard": "I/N", "jobs": J, "scenario": ...}
#     for t = I, I+N, ... < T
#   fake_twinbench.sh study-merge D1 D2 ... --out D
#     writes D/trials.jsonl: the shards' lines, sorted by trial
# FAKE_TWINBENCH_FAIL_SHARD=I makes shard I fail (exit 3) after writing nothing.
set -euo pipefail

die() { echo "fake_twinbench: $*" >&2; exit 2; }

[ $# -ge 1 ] || die "usage: study ... | study-merge ..."
verb="$1"
shift
case "$verb" in
  study)
    [ $# -ge 1 ] || die "study: missing SCENARIO"
    scenario="$1"
    shift
    trials="" shard="" jobs="" out=""
    while [ $# -gt 0 ]; do
      [ $# -ge 2 ] || die "study: $1 needs a value"
      case "$1" in
        --trials) trials="$2" ;;
        --shard) shard="$2" ;;
        --jobs) jobs="$2" ;;
        --out) out="$2" ;;
        *) die "study: unknown option $1" ;;
      esac
      shift 2
    done
    [[ "$trials" =~ ^[0-9]+$ ]] || die "study: --trials '$trials'"
    [[ "$shard" =~ ^([0-9]+)/([0-9]+)$ ]] || die "study: --shard '$shard'"
    i="${BASH_REMATCH[1]}" n="${BASH_REMATCH[2]}"
    ((i < n)) || die "study: --shard $shard"
    [[ "$jobs" =~ ^[1-9][0-9]*$ ]] || die "study: --jobs '$jobs'"
    [ -n "$out" ] || die "study: missing --out"
    if [ "${FAKE_TWINBENCH_FAIL_SHARD:-}" = "$i" ]; then
      echo "fake_twinbench: shard $i fails as asked" >&2
      exit 3
    fi
    mkdir -p "$out"
    : >"$out/trials.jsonl.partial"
    for ((t = i; t < trials; t += n)); do
      printf '{"trial": %d, "shard": "%s", "jobs": %d, "scenario": "%s"}\n' \
        "$t" "$shard" "$jobs" "$scenario" >>"$out/trials.jsonl.partial"
    done
    mv "$out/trials.jsonl.partial" "$out/trials.jsonl"
    ;;
  study-merge)
    dirs=() out=""
    while [ $# -gt 0 ]; do
      case "$1" in
        --out)
          [ $# -ge 2 ] || die "study-merge: --out needs a value"
          out="$2"
          shift 2
          ;;
        *) dirs+=("$1"); shift ;;
      esac
    done
    [ -n "$out" ] || die "study-merge: missing --out"
    [ ${#dirs[@]} -gt 0 ] || die "study-merge: no shard folders"
    files=()
    for d in "${dirs[@]}"; do
      [ -f "$d/trials.jsonl" ] || die "study-merge: no $d/trials.jsonl"
      files+=("$d/trials.jsonl")
    done
    mkdir -p "$out"
    # "{"trial": N, ...": field 2 after ':' starts with the trial number.
    sort -t: -k2,2n "${files[@]}" >"$out/trials.jsonl"
    ;;
  *) die "unknown verb $verb" ;;
esac
