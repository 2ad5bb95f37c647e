#!/usr/bin/env bash
# The clean-arm discovery table (for docs/results/; it prints it on stdout): on each shipped arm and on the
# UR5e test fixture (tests/data/ur5e.urdf, an arm the repository does not ship), a scenario
# written by `twinbench new-scenario --procedure PROCEDURE` (geometry errors and encoder noise
# only: nothing for discovery to find), then a seeded study of TRIALS trials with the diagnosis
# on. Per arm: how many trials' verdicts are consistent_with_noise (every robot's, for an
# optical-axis run: both arms are calibrated), the others by verdict, the effects added, the
# residual test's median p value and the calibrated truth RMS. Target (issue 39): consistent
# with the noise in at least 19 of 20.
# Usage: [ARMS="models/x.urdf ..."] [REUSE=1] scripts/clean_arms_table.sh [TRIALS] [OUT_DIR] [tracker|optical-axis]
#   defaults: 20, out/clean_arms, tracker. Prints the table (markdown) on stdout. Needs a build
#   (scripts/build.sh) and jq. TWINBENCH: another binary. REUSE=1: an arm whose study in OUT
#   has TRIALS finished trials is tabled as it is, not rerun. A scenario file already in OUT
#   (from an earlier run of this script) is used as it is: new-scenario never overwrites.
set -euo pipefail
cd "$(dirname "$0")/.."
TRIALS="${1:-20}"
OUT="${2:-out/clean_arms}"
PROCEDURE="${3:-tracker}"
BIN="${TWINBENCH:-build/bin/twinbench}"
[ -x "$BIN" ] || { echo "clean_arms_table: build first (scripts/build.sh)" >&2; exit 2; }
command -v jq >/dev/null || { echo "clean_arms_table: needs jq (scripts/install_deps.sh)" >&2; exit 2; }
case "$PROCEDURE" in
  tracker|optical-axis) ;;
  *) echo "clean_arms_table: procedure must be tracker or optical-axis, got '$PROCEDURE'" >&2; exit 2 ;;
esac
ARMS_GIVEN="${ARMS:-}"
ARMS="${ARMS:-models/reinovo_r1.yaml models/reinovo_r2.yaml models/abb_irb2400.urdf models/kuka_kr6r900sixx.urdf models/motoman_sda10_right.yaml tests/data/ur5e.urdf}"
for arm in $ARMS; do   # every arm checked before anything is written or run
  [ -f "$arm" ] || { echo "clean_arms_table: no arm model '$arm'" >&2; exit 2; }
done
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
STARTED="$(date -u '+%Y-%m-%d %H:%M UTC')"
for arm in $ARMS; do
  name="$(basename "${arm%.*}")"
  scenario="$OUT/$name.yaml"
  [ -f "$scenario" ] || "$BIN" new-scenario --robot "$arm" --procedure "$PROCEDURE" --out "$scenario" >&2
  if [ "${REUSE:-0}" = 1 ] && [ -s "$OUT/$name/trials.jsonl" ] &&
     [ "$(wc -l < "$OUT/$name/trials.jsonl")" -eq "$TRIALS" ]; then continue; fi
  "$BIN" study "$scenario" --trials "$TRIALS" --jobs 2 --out "$OUT/$name" >&2
done
printf '# Model discovery on clean arms, %s procedure\n\n' "$PROCEDURE"
printf -- '- date: %s (started), %s (this table)\n- commit: %s\n' "$STARTED" "$(date -u '+%Y-%m-%d %H:%M UTC')" \
  "$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- calib sim bench || echo ' (with uncommitted changes)')"
printf -- '- machine: %s, %s cores, %s GiB\n' "$(uname -m)" "$(nproc)" \
  "$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo)"
printf -- '- command: `%s%s%sscripts/clean_arms_table.sh %s %s %s`\n' "${TWINBENCH:+TWINBENCH=$TWINBENCH }" \
  "${REUSE:+REUSE=$REUSE }" "${ARMS_GIVEN:+ARMS=\"$ARMS\" }" "$TRIALS" "$OUT" "$PROCEDURE"
printf -- '- binary: %s\n' "$("$BIN" --version)"
printf -- '- per arm: `twinbench new-scenario --robot ARM --procedure %s --out S` (geometry errors and encoder noise, nothing else), then `twinbench study S --trials %s --jobs 2`: trial t draws the truth from seeds.truth + t and the estimator randomness from seeds.estimator + t\n' "$PROCEDURE" "$TRIALS"
printf -- '- consistent: every calibrated robot'"'"'s `diagnosis.verdict` is consistent_with_noise (target: 19 of 20); p: the median over trials of the smallest residual-test p value (after the last step) of the trial'"'"'s robots; truth RMS: the mean of truth_position_error_mm.rigid.after.rms (of every robot)\n\n'
printf '| arm | trials | consistent with noise | effects_added | partly_explained | unexplained | failed | effects added (trials) | median p | truth RMS [mm] |\n'
printf '|---|---|---|---|---|---|---|---|---|---|\n'
for arm in $ARMS; do
  name="$(basename "${arm%.*}")"
  jq -s -r --arg arm "$arm" '
    def verdicts: [.labels | to_entries[] | select(.key | test("(^|\\.)diagnosis\\.verdict$")) | .value];
    def worst: (verdicts) as $v |
      if ($v | length) == 0 then "failed"
      elif ($v | index("unexplained")) then "unexplained"
      elif ($v | index("partly_explained")) then "partly_explained"
      elif ($v | index("effects_added")) then "effects_added"
      else "consistent_with_noise" end;
    def added: [.labels | to_entries[] | select(.key | test("(^|\\.)diagnosis\\.effects_added\\[[0-9]+\\]\\.label$")) | .value];
    def pmin: [.figures | to_entries[] | select(.key | test("(^|\\.)diagnosis\\.residual_test\\.after\\.p_value$")) | .value] | min;
    def rms: [.figures | to_entries[] | select(.key | test("(^|\\.)truth_position_error_mm\\.rigid\\.after\\.rms$")) | .value];
    def median: sort | if length == 0 then null elif length % 2 == 1 then .[length / 2 | floor] else (.[length / 2 - 1] + .[length / 2]) / 2 end;
    (map(select(.status == "ok"))) as $ok |
    ($ok | map(worst)) as $w |
    ([$ok[] | added[]] | group_by(.) | map("\(.[0]) (\(length))") | join("; ")) as $names |
    ([$ok[] | pmin | select(. != null)] | median) as $p |
    ([$ok[] | rms[]]) as $r |
    "| \($arm) | \(length) | \($w | map(select(. == "consistent_with_noise")) | length) of \(length) | \($w | map(select(. == "effects_added")) | length) | \($w | map(select(. == "partly_explained")) | length) | \($w | map(select(. == "unexplained")) | length) | \((length - ($ok | length)) + ($w | map(select(. == "failed")) | length)) | \(if $names == "" then "-" else $names end) | \(if $p == null then "-" else ($p * 1000 | round / 1000) end) | \(if ($r | length) == 0 then "-" else (($r | add / length) * 10000 | round / 10000) end) |"' \
    "$OUT/$name/trials.jsonl"
done
