#!/usr/bin/env bash
# The model-discovery table (docs/results/; the terms it counts are explained in
# docs/explanation/discovery-statistics.md): a seeded study of every
# scenario in scenarios/discovery/ (20 trials each by default; each trial a different truth and
# estimator seed), then per scenario: how often the injected (undeclared) effect was named,
# how often something else was added, and the physical-truth RMS (rigid gauge, the twin's
# reflector with every effect against the model at the same readings) of the geometric-only
# model, of the discovered one and of the same trials without the effect (*_clean.yaml).
# Usage: [SCENARIOS="clean other ..."] [REUSE=1] scripts/discovery_table.sh [TRIALS] [OUT_DIR] [tracker|optical]
#   tracker (default): the laser-tracker scenarios; optical: the optical-axis ones (robot r2,
#   the board's feature point instead of the reflector). Needs a build: scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
TRIALS="${1:-20}"
PROCEDURE="${3:-tracker}"
OUT="${2:-out/discovery}"
BIN="${TWINBENCH:-build/bin/twinbench}"   # TWINBENCH: another build (e.g. a copy while rebuilding)
[ -x "$BIN" ] || { echo "discovery_table: build first (scripts/build.sh)" >&2; exit 2; }
command -v jq >/dev/null || { echo "discovery_table: needs jq (scripts/install_deps.sh)" >&2; exit 2; }
mkdir -p "$OUT"
declare -A INJECTED=(
  [tracker_clean]=""
  [tracker_compliance_j2]="joint_compliance (joint 2)"
  [tracker_compliance_j2_declared]=""
  [tracker_transmission_j1]="transmission_error (joint 1, order 1)"
  [tracker_backlash_j3]="backlash (joint 3)"
  [tracker_thermal_drift]="thermal_"   # thermal_drift or thermal_warmup (any time constant)
  [tracker_thermal_drift_sensed]="thermal_"   # the same with the arm's temperature sensor
  [tracker_thermal_drift_declared]=""   # the same warm-up declared (the estimator's warm-up)
  [tracker_lateral_compliance_j2]="lateral_compliance (joint 2)"
  [tracker_lateral_compliance_j2_declared]=""   # the same declared: the control of its RMS
  [tracker_base_compliance]="lateral_compliance (joint 1)"   # the estimator's base tilt
  [tracker_axis_wobble_j1]="axis_wobble (joint 1, order 2)"
  [tracker_transmission_j2_order3]="transmission_error (joint 2, order 3)"
  [optical_clean]=""
  [optical_clean_reseeded]=""   # the clean truths, other images: the pair scatter of the rows
  [optical_compliance_j2]="joint_compliance (joint 2)"
  [optical_compliance_j2_declared]=""
  [optical_transmission_j3]="transmission_error (joint 3, order 1)"
  [optical_backlash_j3]="backlash (joint 3)"
  [optical_thermal_drift]="thermal_"   # thermal_drift or thermal_warmup (any time constant)
  [optical_thermal_drift_sensed]="thermal_"   # the same with the arm's temperature sensor
  [optical_mount_deflection]="mount_deflection"
  [optical_lateral_compliance_j2]="lateral_compliance (joint 2)"
  [optical_base_compliance]="lateral_compliance (joint 1)"
  [optical_axis_wobble_j1]="axis_wobble (joint 1, order 2)"
  [optical_lateral_compliance_j2_declared]=""   # the same effects declared: the control of
  [optical_base_compliance_declared]=""         # what the procedure's data can reach with
  [optical_axis_wobble_j1_declared]=""          # the term in the model
)
case "$PROCEDURE" in
  tracker)
    ORDER=(tracker_clean tracker_compliance_j2 tracker_transmission_j1 tracker_backlash_j3
           tracker_thermal_drift tracker_thermal_drift_sensed tracker_thermal_drift_declared
           tracker_compliance_j2_declared tracker_lateral_compliance_j2
           tracker_lateral_compliance_j2_declared tracker_base_compliance
           tracker_axis_wobble_j1 tracker_transmission_j2_order3)
    PREFIX="" ;;
  optical)
    ORDER=(optical_clean optical_clean_reseeded optical_compliance_j2 optical_transmission_j3
           optical_backlash_j3
           optical_thermal_drift optical_thermal_drift_sensed optical_mount_deflection
           optical_compliance_j2_declared optical_lateral_compliance_j2
           optical_lateral_compliance_j2_declared optical_base_compliance
           optical_base_compliance_declared optical_axis_wobble_j1 optical_axis_wobble_j1_declared)
    PREFIX="robots.r2." ;;
  *) echo "discovery_table: procedure must be tracker or optical, got '$PROCEDURE'" >&2; exit 2 ;;
esac
# SCENARIOS="a b ...": only these (the clean one of the procedure first), e.g. to add a row.
if [ -n "${SCENARIOS:-}" ]; then read -r -a ORDER <<< "$SCENARIOS"; fi
CLEAN="${ORDER[0]}"
# REUSE=1: a scenario whose study is already in OUT (trials.jsonl) is tabled as it is, not rerun.
for s in "${ORDER[@]}"; do
  # (only a finished study of exactly TRIALS trials: an interrupted one is run again)
  if [ "${REUSE:-0}" = 1 ] && [ -s "$OUT/$s/trials.jsonl" ] &&
     [ "$(wc -l < "$OUT/$s/trials.jsonl")" -eq "$TRIALS" ]; then continue; fi
  "$BIN" study "scenarios/discovery/$s.yaml" --trials "$TRIALS" --jobs 2 --out "$OUT/$s" >&2
done
# Per trial: trial, effects added (labels joined by ;), geometric-only and discovered RMS over
# the whole joint space, then the same over the covered region (optical runs; nan otherwise),
# then the candidates the verdict names as indistinguishable from an added effect (joined by ;),
# then those it names as where an effect could be there unseen (could_hide, joined by ;).
rows() {
  jq -r --arg p "$PREFIX" '[.trial,
          ([.labels | to_entries[] | select(.key | startswith($p)) | select(.key[($p | length):] | test("^diagnosis\\.effects_added\\[[0-9]+\\]\\.label$")) | .value] | join(";")),
          (.figures[$p + "truth_position_error_mm_physical.calibrated_model.rigid.rms"] // "nan"),
          (.figures[$p + "truth_position_error_mm_discovered_model.rigid.rms"] // "nan"),
          (.figures[$p + "truth_position_error_mm_physical_covered_region.calibrated_model.rigid.rms"] // "nan"),
          (.figures[$p + "truth_position_error_mm_physical_covered_region.discovered_model.rigid.rms"] // "nan"),
          ([.labels | to_entries[] | select(.key | startswith($p)) | select(.key[($p | length):] | test("^diagnosis\\.effects_added\\[[0-9]+\\]\\.indistinguishable_from\\[[0-9]+\\]$")) | .value] | join(";")),
          ([.labels | to_entries[] | select(.key | startswith($p)) | select(.key[($p | length):] | test("^diagnosis\\.could_hide\\[[0-9]+\\]$")) | .value] | join(";"))] | @tsv' \
     "$OUT/$1/trials.jsonl" | sort -t$'\t' -k1,1
}
rows "$CLEAN" > "$OUT/clean.tsv"
# Provenance (docs/results/ tables are written by this script, never by hand).
printf '# Model discovery on the twin, %s procedure\n\n' "$PROCEDURE"
printf -- '- date: %s\n- commit: %s\n- machine: %s, %s cores, %s GiB\n' "$(date -u '+%Y-%m-%d %H:%M UTC')" \
  "$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- calib sim bench || echo ' (with uncommitted changes)')" \
  "$(uname -m)" "$(nproc)" "$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo)"
printf -- '- command: `%s%s%sscripts/discovery_table.sh %s %s %s`\n' \
  "${TWINBENCH:+TWINBENCH=$TWINBENCH }" "${REUSE:+REUSE=$REUSE }" \
  "${SCENARIOS:+SCENARIOS=\"$SCENARIOS\" }" "$TRIALS" "$OUT" "$PROCEDURE"
printf -- '- binary: %s\n' "$("$BIN" --version)"
printf -- '- %s trials a scenario: trial t draws the truth from seeds.truth + t and the estimator randomness from seeds.estimator + t of the scenario (twinbench study)\n\n' "$TRIALS"
printf '| scenario | injected (undeclared) | named | named, or named indistinguishable from the effect added | something else added | truth RMS geometric-only [mm] | discovered [mm] | effect-free [mm] | not named, but named where an effect could be unseen | discovered <= 1.2 x effect-free | covered region: geometric-only / discovered / effect-free [mm] | covered: within 1.2 x |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|---|\n'
for s in "${ORDER[@]}"; do
  rows "$s" > "$OUT/$s.tsv"
  join -t $'\t' "$OUT/$s.tsv" "$OUT/clean.tsv" | awk -F'\t' -v inj="${INJECTED[$s]}" -v name="$s" '
    # $1-$8: this scenario (trial, added, RMS x4, indistinguishable, could hide); $9-$15: the
    # clean one.
    { n++; named += (inj != "" && index($2, inj) > 0)
      hit = inj != "" && (index($2, inj) > 0 || index($7, inj) > 0); named_any += hit
      unseen += (inj != "" && !hit && index($8, inj) > 0)
      split($2, added, ";")
      for (k in added) if (added[k] != "" && (inj == "" || index(added[k], inj) == 0)) { other++; break }
      g += $3; d += $4; f += $10; within += ($4 <= 1.2 * $10)
      if ($6 != "nan" && $12 != "nan") { nc++; gc += $5; dc += $6; fc += $12; withinc += ($6 <= 1.2 * $12) } }
    END { covered = nc > 0 ? sprintf("%.4f / %.4f / %.4f | %d of %d", gc / nc, dc / nc, fc / nc, withinc, nc) : "- | -"
          printf "| %s | %s | %s | %s | %d of %d | %.4f | %.4f | %.4f | %s | %d of %d | %s |\n", name,
          (inj == "" ? "none" : inj), (inj == "" ? "-" : named " of " n),
          (inj == "" ? "-" : named_any " of " n), other, n, g / n, d / n,
          f / n, (inj == "" ? "-" : unseen " of " n), within, n, covered }'
done
