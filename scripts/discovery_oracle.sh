#!/usr/bin/env bash
# The oracle control of model discovery's rows (docs/results/discovery_oracle.md; the columns are
# explained in docs/explanation/discovery-statistics.md, "The oracle control").
# Per scenario of scenarios/discovery/, its trials 0..TRIALS-1 run twice with `twinbench run
# --trial t` (a study keeps no candidate lists):
#   - as written: the search's own verdict and the candidates of its first fit;
#   - a copy whose diagnosis is told the injected term (SPEC: TYPE[:JOINT[:ORDERS]], the term
#     alone as the one candidate; scripts/discovery_oracle.py given).
# Both share the truths, the noise and the plan. Then one row per scenario (discovery_oracle.py
# row): how often the search named the term, and how often the term's own test, with no
# multiplicity, calls it present. Fewer than a target's count there means no search can meet
# that target on these data.
# CLEAN="S ...": scenarios without an effect, run as written, for a second table: the same test's
# share below 0.05 and 0.005 over every candidate (whether the floor keeps the test's level).
# Usage: [TWINBENCH=BIN] [JOBS=2] [CLEAN="S ..."] scripts/discovery_oracle.sh TRIALS OUT SCENARIO=SPEC ...
#   e.g. scripts/discovery_oracle.sh 20 out/oracle optical_base_compliance=lateral_compliance:1
#   OUT: a new folder, or one this script wrote (a trial whose report is there is not run
#   again). The section goes to the top of docs/results/discovery_oracle.md (ORACLE_DOC: another
#   file, the script's test). Needs a build (scripts/build.sh) and python3-yaml.
set -euo pipefail
cd "$(dirname "$0")/.."
usage() { echo "usage: scripts/discovery_oracle.sh TRIALS OUT SCENARIO=SPEC ..." >&2; exit 2; }
[ $# -ge 3 ] || usage
TRIALS="$1"; OUT="$2"; shift 2
[[ "$TRIALS" =~ ^[1-9][0-9]*$ ]] || { echo "discovery_oracle: TRIALS must be a positive integer, got '$TRIALS'" >&2; exit 2; }
BIN="${TWINBENCH:-build/bin/twinbench}"
JOBS="${JOBS:-2}"
DOC="${ORACLE_DOC:-docs/results/discovery_oracle.md}"
[ -x "$BIN" ] || { echo "discovery_oracle: build first (scripts/build.sh), or set TWINBENCH" >&2; exit 2; }
read -r -a CLEANS <<< "${CLEAN:-}"
for s in "${CLEANS[@]}"; do
  [ -f "scenarios/discovery/$s.yaml" ] || { echo "discovery_oracle: no scenarios/discovery/$s.yaml" >&2; exit 2; }
done
for arg in "$@"; do
  s="${arg%%=*}"; spec="${arg#*=}"
  [ "$s" != "$arg" ] && [ -n "$spec" ] || { echo "discovery_oracle: '$arg' is not SCENARIO=SPEC" >&2; exit 2; }
  [ -f "scenarios/discovery/$s.yaml" ] || { echo "discovery_oracle: no scenarios/discovery/$s.yaml" >&2; exit 2; }
done
if [ -e "$OUT" ] && [ ! -f "$OUT/.discovery-oracle" ]; then
  echo "discovery_oracle: $OUT exists and this script did not write it; name a new folder" >&2; exit 2
fi
mkdir -p "$OUT"; touch "$OUT/.discovery-oracle"

# run_trials SCENARIO_FILE RUNS PLANS: trials 0..TRIALS-1, the first alone (it fills the plan
# cache), then JOBS at a time; a trial whose report.json exists is kept.
run_trials() {
  local file="$1" runs="$2" plans="$3"
  mkdir -p "$runs"
  one() {
    [ -f "$2/$4/report.json" ] && return 0
    rm -rf "$2/$4"
    if ! "$BIN" run "$1" --trial "$4" --out "$2/$4" --quiet --no-images --plan-cache "$3" > "$2/$4.log" 2>&1; then
      # exit 3: the run missed its acceptance targets; its report is complete
      [ -f "$2/$4/report.json" ] || { echo "discovery_oracle: $1 trial $4 failed (log: $2/$4.log)" >&2; return 1; }
    fi
    echo "discovery_oracle: $(basename "$1") trial $4 done" >&2
  }
  export -f one; export BIN
  one "$file" "$runs" "$plans" 0
  seq 1 $((TRIALS - 1)) | xargs -r -P "$JOBS" -I{} bash -c 'one "$@"' _ "$file" "$runs" "$plans" {}
}

section="$OUT/section.md"
{
  printf '## Run of %s\n\n' "$(date -u '+%Y-%m-%d %H:%M UTC')"
  printf -- '- date: %s\n- commit: %s\n- machine: %s, %s cores, %s GiB\n' "$(date -u '+%Y-%m-%d %H:%M UTC')" \
    "$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- calib sim bench || echo ' (with uncommitted changes)')" \
    "$(uname -m)" "$(nproc)" "$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo)"
  printf -- '- command: `%s%sscripts/discovery_oracle.sh %s %s %s`\n' "${TWINBENCH:+TWINBENCH=$TWINBENCH }" \
    "${CLEAN:+CLEAN=\"$CLEAN\" }" "$TRIALS" "$OUT" "$*"
  printf -- '- binary: %s\n' "$("$BIN" --version)"
  printf -- '- trials 0-%d of each scenario (truth seed + t, estimator seed + t), each run as written and told the term\n\n' "$((TRIALS - 1))"
  printf '| scenario | injected term (told in the control) | trials | named by the search | named by type and joint (any order) | named, or named indistinguishable from the term added | told the term: its own test p < 0.05 | p < 0.05 / m (m: the candidates of the first fit) | ranked first among those candidates | ranked first instead, most often | told the term: unidentifiable |\n'
  printf '|---|---|---|---|---|---|---|---|---|---|---|\n'
} > "$section.new"
for arg in "$@"; do
  s="${arg%%=*}"; spec="${arg#*=}"
  mkdir -p "$OUT/$s"
  [ -f "$OUT/$s/given.yaml" ] ||
    python3 scripts/discovery_oracle.py given "scenarios/discovery/$s.yaml" "$spec" "$OUT/$s/given.yaml"
  run_trials "scenarios/discovery/$s.yaml" "$OUT/$s/search" "$OUT/$s/plans"
  run_trials "$OUT/$s/given.yaml" "$OUT/$s/given" "$OUT/$s/plans"
  python3 scripts/discovery_oracle.py row "$s" "$OUT/$s/search" "$OUT/$s/given" >> "$section.new"
done
printf '\n' >> "$section.new"
if [ ${#CLEANS[@]} -gt 0 ]; then
  { printf 'The same size test on scenarios without an effect, over every candidate of the first fit of every trial (at its level: about 5 %% and 0.5 %%):\n\n'
    printf '| scenario (no effect) | trials | candidates fitted | p < 0.05 | p < 0.005 |\n|---|---|---|---|---|\n'; } >> "$section.new"
  for s in "${CLEANS[@]}"; do
    run_trials "scenarios/discovery/$s.yaml" "$OUT/$s/search" "$OUT/$s/plans"
    python3 scripts/discovery_oracle.py level "$s" "$OUT/$s/search" >> "$section.new"
  done
  printf '\n' >> "$section.new"
fi
mv "$section.new" "$section"
. scripts/lib/results_doc.sh
insert_section "$DOC" "$section" <<'INTRO'
# The oracle control of model discovery on the twin

Written by `scripts/discovery_oracle.sh` (newest first). Each row: a scenario's trials run
as written and with the diagnosis told the injected term; what the columns mean is in
docs/explanation/discovery-statistics.md ("The oracle control").
INTRO
echo "wrote $DOC" >&2
