#!/usr/bin/env bash
# A lever's paired study (issue 42; docs/explanation/studies.md): each scenario run as a study
# of TRIALS trials by the build before the change and by the build after it, on the same trials
# (the same truth and estimator seeds), then scripts/compare_studies.sh on each pair, whose last
# part is the acceptance rule (scripts/paired_verdict.py). The section it writes goes at the top
# of docs/results/paired_studies.md (older sections stay below), with the date, the commit, both
# builds' versions, the commands, each pair's figures and verdict, and each build's mean trial
# wall time and its plan's compute time (as the studies ran them: contended when other work ran).
# Usage: [REUSE=1] scripts/paired_study_table.sh TITLE BEFORE_BIN AFTER_BIN TRIALS OUT SCENARIO...
#   OUT/SCENARIO_before and OUT/SCENARIO_after are the studies (REUSE=1: a study already holding
#   TRIALS trials is tabled as it is, not run again). SCENARIO: a file of scenarios/ without .yaml,
#   or BEFORE:AFTER, two such files (the before build runs the first, the after build the
#   second; a control, with BEFORE_BIN = AFTER_BIN and the second differing in one setting, such
#   as scenarios/controls/paper_reinovo_renoised.yaml, whose trials share only their truth seeds
#   with the first's: compare_studies.sh --control). The studies are OUT/BEFORE_before and
#   OUT/BEFORE_after, with any / of BEFORE written _.
#   Exit 0 when every pair is accepted, 1 when one is not, 2 on bad input.
#   PAIRED_DOC: another file to write than docs/results/paired_studies.md (the script's test).
#   NOTE: a line printed under the section's header (what ran beside the studies, ...).
#   CONTROL=DIR CONTROL_NOTE=TEXT: a control of the first scenario, a study of TRIALS trials
#   made by the before build with a change that should not matter (TEXT says which; the same
#   truth seeds, the noise and estimator seeds may differ): the rule
#   run on the before study against it follows the pair's, to show the rule's own scatter.
#   Its verdict does not change the exit status.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 6 ] || { echo "usage: $0 TITLE BEFORE_BIN AFTER_BIN TRIALS OUT SCENARIO..." >&2; exit 2; }
TITLE="$1" BEFORE_BIN="$2" AFTER_BIN="$3" TRIALS="$4" OUT="$5"
shift 5
SCENARIOS=("$@")
DOC="${PAIRED_DOC:-docs/results/paired_studies.md}"
[[ "$TRIALS" =~ ^[0-9]+$ ]] && [ "$TRIALS" -ge 40 ] ||
  { echo "paired_study_table: TRIALS '$TRIALS': the rule needs at least 40" >&2; exit 2; }
for b in "$BEFORE_BIN" "$AFTER_BIN"; do
  [ -x "$b" ] || { echo "paired_study_table: $b: not an executable" >&2; exit 2; }
done
before_of() { echo "${1%%:*}"; }                      # SCENARIO or BEFORE:AFTER -> BEFORE
after_of() { [[ "$1" == *:* ]] && echo "${1#*:}" || echo "$1"; }
stem_of() { local b; b=$(before_of "$1"); echo "${b//\//_}"; }  # the studies' folder stem
for sc in "${SCENARIOS[@]}"; do
  [[ "$sc" != *:*:* && "$sc" != :* && "$sc" != *: ]] ||
    { echo "paired_study_table: '$sc': expected SCENARIO or BEFORE:AFTER" >&2; exit 2; }
  for f in "$(before_of "$sc")" "$(after_of "$sc")"; do
    [ -f "scenarios/$f.yaml" ] || { echo "paired_study_table: scenarios/$f.yaml: not found" >&2; exit 2; }
  done
done
if [ -n "${CONTROL:-}" ]; then
  [ -n "${CONTROL_NOTE:-}" ] || { echo "paired_study_table: CONTROL needs CONTROL_NOTE (what it changes)" >&2; exit 2; }
  n=0
  [ -s "$CONTROL/trials.jsonl" ] && n=$(wc -l <"$CONTROL/trials.jsonl")
  [ "$n" -ge "$TRIALS" ] ||
    { echo "paired_study_table: CONTROL $CONTROL: $n trials, the pair has $TRIALS" >&2; exit 2; }
fi
command -v jq >/dev/null || { echo "paired_study_table: needs jq (scripts/install_deps.sh)" >&2; exit 2; }
mkdir -p "$OUT"

commands=()
study() {  # BIN SCENARIO DIR
  local cmd="$1 study scenarios/$2.yaml --trials $TRIALS --out $3 --quiet"
  commands+=("$cmd")
  local have=0
  [ -s "$3/trials.jsonl" ] && have=$(wc -l <"$3/trials.jsonl")
  if [ "${REUSE:-0}" = 1 ] && [ "$have" -ge "$TRIALS" ]; then
    echo "reusing $3 ($have trials)" >&2
  else
    echo "running: $cmd" >&2
    $cmd
  fi
}
for sc in "${SCENARIOS[@]}"; do
  study "$BEFORE_BIN" "$(before_of "$sc")" "$OUT/$(stem_of "$sc")_before"
  study "$AFTER_BIN" "$(after_of "$sc")" "$OUT/$(stem_of "$sc")_after"
done

# Mean wall time of a trial as the study ran it, and the compute time of the plan its trials
# share (timing_s.planning_compute: every trial reports the stored plan's) [s].
timing() {
  jq -rs '[.[] | select(.run.wall_s != null)] as $t | ($t | length) as $n |
    if $n == 0 then "no timed trials" else
    "\($n) trials: \(([$t[].run.wall_s] | add / $n * 10 | round / 10)) s a trial; the plan computed in \(([$t[].run.timing["timing_s.planning_compute"] // 0] | max * 10 | round / 10)) s (both robots summed; the trials share it)" end' \
    "$1/trials.jsonl"
}

section=$(mktemp)
status=0
{
  echo "## $TITLE ($(date -u '+%Y-%m-%d %H:%M UTC'))"
  echo
  echo "- commit: $(git rev-parse --short HEAD)"
  echo "- before: $("$BEFORE_BIN" --version); after: $("$AFTER_BIN" --version)"
  echo "- machine: $(uname -m), $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo) GiB"
  echo "- command: \`${REUSE:+REUSE=$REUSE }scripts/paired_study_table.sh \"$TITLE\" $BEFORE_BIN $AFTER_BIN $TRIALS $OUT ${SCENARIOS[*]}\`, whose studies are:"
  echo
  for c in "${commands[@]}"; do echo "      $c"; done
  if [ -n "${NOTE:-}" ]; then echo; echo "$NOTE"; fi
  for sc in "${SCENARIOS[@]}"; do
    echo
    if [[ "$sc" == *:* ]]; then
      echo "### $(before_of "$sc") (before) against $(after_of "$sc") (after)"
    else
      echo "### $sc"
    fi
    echo
    echo '```'
    last=$((TRIALS - 1))
    half=$((TRIALS / 2))
    stem="$OUT/$(stem_of "$sc")"
    control=()  # BEFORE:AFTER: a control; its trials share the truth seed only
    [[ "$sc" == *:* ]] && control=(--control)
    if scripts/compare_studies.sh ${control[@]+"${control[@]}"} "${stem}_before" "${stem}_after" "0-$((half - 1))" "$half-$last" 2>&1; then
      :
    else
      rc=$?
      [ $rc -eq 1 ] && status=1 || status=2
    fi
    echo "time, before: $(timing "${stem}_before")"
    echo "time, after:  $(timing "${stem}_after")"
    echo '```'
    if [ -n "${CONTROL:-}" ] && [ "$sc" = "${SCENARIOS[0]}" ]; then
      echo
      echo "#### $(before_of "$sc"): control ($CONTROL_NOTE)"
      echo
      echo "The rule on the before study against the control: how far the rule moves when"
      echo "nothing that should matter changed. Its verdict does not count."
      echo
      echo '```'
      scripts/compare_studies.sh --control "${stem}_before" "$CONTROL" "0-$((half - 1))" "$half-$last" 2>&1 || true
      echo '```'
    fi
  done
  echo
} >"$section"
. scripts/lib/results_doc.sh
insert_section "$DOC" "$section" <<'INTRO'
# Paired studies of changes that move figures

Written by `scripts/paired_study_table.sh` (newest first). Each section: a change's studies
before and after on the same trials, and the acceptance rule of issue 42
(scripts/paired_verdict.py, docs/explanation/studies.md) on each scenario. The times are
as the studies ran (two trial processes at a time); other work on the machine shows in them.
INTRO
rm -f "$section"
echo "wrote $DOC" >&2
exit $status
