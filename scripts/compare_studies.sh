#!/usr/bin/env bash
# Accuracy of two studies of an optical-axis scenario on the same seeds, side by side
# (docs/explanation/studies.md: accuracy before and after a change). Per range of trials: the seeds whose robots
# all meet the truth targets (rigid RMS <= 0.3 mm and similarity RMS <= 0.1 mm, "Over other
# seeds"), the median and worst rigid, similarity and validation (misaligned, held-out axes)
# errors, the scale error (estimated / true - 1) RMS and worst; then, over the trials both
# hold, the paired change of each robot's similarity figure.
# Last, the acceptance rule for a change that moves figures (scripts/paired_verdict.py): its
# figures and verdict, and its exit status (0 accepted, 1 rejected, 2 bad input).
# Usage: scripts/compare_studies.sh [--control] BEFORE_DIR AFTER_DIR [FIRST-LAST ...]
#   (default ranges: 1-20 21-40 41-60); each DIR holds a study's trials.jsonl.
#   --control: AFTER_DIR is a control study of another noise or estimator seed
#   (paired_verdict.py --control: trials paired by their truth seed alone).
set -euo pipefail
VERDICT_ARGS=()
if [ "${1:-}" = --control ]; then VERDICT_ARGS=(--control); shift; fi
[ $# -ge 2 ] || { echo "usage: $0 [--control] BEFORE_DIR AFTER_DIR [FIRST-LAST ...]" >&2; exit 2; }
command -v jq >/dev/null || { echo "compare_studies: needs jq (scripts/install_deps.sh)" >&2; exit 2; }
BEFORE="$1/trials.jsonl"
AFTER="$2/trials.jsonl"
shift 2
for f in "$BEFORE" "$AFTER"; do
  [ -s "$f" ] || { echo "compare_studies: $f: no such file or empty" >&2; exit 2; }
done
RANGES=("$@")
[ ${#RANGES[@]} -gt 0 ] || RANGES=(1-20 21-40 41-60)

# One line per robot calibration: trial robot rigid similarity validation scale_error
rows() {
  jq -r 'select(.figures != null) | .trial as $t | .figures as $f | ["r1", "r2"][] as $r |
    [$t, $r,
     $f["robots.\($r).truth_position_error_mm.rigid.after.rms"],
     $f["robots.\($r).truth_position_error_mm.similarity.after.rms"],
     ($f["robots.\($r).misaligned_error_mm.validation.after"] // "nan"),
     (if $f["robots.\($r).scale.estimated"] == null then "nan"
      else $f["robots.\($r).scale.estimated"] / $f["robots.\($r).scale.true"] - 1 end)]
    | select(.[2] != null and .[3] != null) | @tsv' "$1"
}

summary() {  # file first last
  rows "$1" | awk -v a="$2" -v b="$3" -F'\t' '
    function median(x, n,   i, j, t) {
      for (i = 2; i <= n; ++i) { t = x[i]; for (j = i - 1; j >= 1 && x[j] > t; --j) x[j + 1] = x[j]; x[j + 1] = t }
      return n % 2 ? x[(n + 1) / 2] : (x[n / 2] + x[n / 2 + 1]) / 2
    }
    $1 >= a && $1 <= b {
      ++n; rg[n] = $3; sm[n] = $4; if ($3 > wr) wr = $3; if ($4 > ws) ws = $4
      if ($5 != "nan") { ++nv; va[nv] = $5; if ($5 > wv) wv = $5 }
      if ($6 != "nan") { ++nk; ss += $6 * $6; k = $6 < 0 ? -$6 : $6; if (k > wk) wk = k }
      seen[$1] = 1; if (!($3 <= 0.3 && $4 <= 0.1)) missed[$1] = 1
    }
    END {
      if (n == 0) { print "no trials"; exit }
      seeds = 0; met = 0
      for (t in seen) { ++seeds; if (!(t in missed)) ++met }
      printf "%d of %d seeds | rigid %.3f / %.3f | similarity %.3f / %.3f | validation %.3f / %.3f | scale %.1e / %.1e",
        met, seeds, median(rg, n), wr, median(sm, n), ws, nv ? median(va, nv) : 0, wv,
        nk ? sqrt(ss / nk) : 0, wk
    }'
}

printf 'before: %s\nafter:  %s\n' "$BEFORE" "$AFTER"
for range in "${RANGES[@]}"; do
  [[ "$range" =~ ^([0-9]+)-([0-9]+)$ ]] || { echo "compare_studies: range '$range': expected FIRST-LAST" >&2; exit 2; }
  printf 'trials %s\n  before: %s\n  after:  %s\n' "$range" \
    "$(summary "$BEFORE" "${BASH_REMATCH[1]}" "${BASH_REMATCH[2]}")" \
    "$(summary "$AFTER" "${BASH_REMATCH[1]}" "${BASH_REMATCH[2]}")"
done
# Paired similarity changes over the robot calibrations both studies hold.
join -t $'\t' <(rows "$BEFORE" | awk -F'\t' '{print $1 ":" $2 "\t" $4}' | sort) \
              <(rows "$AFTER" | awk -F'\t' '{print $1 ":" $2 "\t" $4}' | sort) |
  awk -F'\t' '{ ++n; d[n] = $3 - $2; if (d[n] < 0) ++lower }
    END {
      if (n == 0) { print "paired: no common trials"; exit }
      for (i = 2; i <= n; ++i) { t = d[i]; for (j = i - 1; j >= 1 && d[j] > t; --j) d[j + 1] = d[j]; d[j + 1] = t }
      m = n % 2 ? d[(n + 1) / 2] : (d[n / 2] + d[n / 2 + 1]) / 2
      printf "paired similarity change (after - before) over %d robot calibrations: median %+.4f mm, lower after in %d\n", n, m, lower
    }'
# The acceptance rule over every paired trial.
exec python3 "$(dirname "$0")/paired_verdict.py" "$(dirname "$BEFORE")" "$(dirname "$AFTER")" ${VERDICT_ARGS[@]+"${VERDICT_ARGS[@]}"}
