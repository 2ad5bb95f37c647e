#!/usr/bin/env python3
"""The acceptance rule for a change that moves figures (issue 42), on a paired study.

A paired study is the same scenario run before and after the change on the same trials (the
same truth and estimator seeds, `twinbench study --trials N`). The change is accepted when, over
at least MIN_TRIALS paired trials:
  1. for each robot and for the rigid and the similarity truth RMS
     (robots.<r>.truth_position_error_mm.{rigid,similarity}.after.rms), the one-sided 95 % upper
     confidence bound of the mean after/before ratio is at most 1.05. The ratio is the ratio of
     the means (mean after / mean before over the paired trials) and its bound the 95th
     percentile of a paired bootstrap (BOOTSTRAP_RESAMPLES resamples of the trials, a fixed
     seed: the same figures on every run);
  2. the share of seeds whose robots all meet the accuracy targets (rigid <= 0.3 mm, similarity
     <= 0.1 mm; a failed trial meets nothing) does not fall;
  3. no robot calibration goes above 0.6 mm rigid that was at or below it before.
A trial that missed its scenario's acceptance targets (exit 3) ran to its report: its figures
count in 1-3 like any other's.
Run it on the paper scenario and on one other arm; a change is accepted where both are.

For information, not in the verdict, it also prints the mean of the per-trial ratios with its
Student's t bound (rule 1 until 2026-12-07). That mean is biased above 1 when a change re-draws
what each trial's error is made of (E[a/b] > E[a]/E[b] for a independent of b): a control that
scaled the image noise by 1.001, nothing else changed, gave 1.030 with the bound 1.067 on the
paper scenario's r1 rigid RMS, and was rejected by it; the ratio of the means gave 1.012, bound
1.038 (docs/results/paired_studies.md).

Usage: scripts/paired_verdict.py BEFORE_DIR AFTER_DIR [--min-trials N] [--control]
  Each DIR holds a study's trials.jsonl (docs/reference/report-json.md). Prints the figures and
  the verdict; exit 0 accepted, 1 rejected or too few paired trials, 2 bad input (a missing
  file, a line that is not JSON, or trials of the same number run on other seeds).
  --control: the after study is a control run on another noise or estimator seed
  (scenarios/controls/): paired trials must share their truth seed only.
Standard library only.
"""
import json
import math
import random
import sys

FIGURE = "robots.{robot}.truth_position_error_mm.{gauge}.after.rms"
GAUGES = ("rigid", "similarity")
TARGETS = {"rigid": 0.3, "similarity": 0.1}  # mm, the accuracy targets of the studies
MAX_RATIO = 1.05      # the upper bound the mean after/before ratio may reach
CROSSING_MM = 0.6     # rigid RMS no robot may newly exceed
CONFIDENCE_Z = 1.6448536269514722  # the standard normal's 95 % quantile (one-sided)
BOOTSTRAP_RESAMPLES = 4000  # over 20 seeds the bound moved with sd 0.002 (r1 rigid, skybox study)


def fail(message):
    print("paired_verdict: " + message, file=sys.stderr)
    sys.exit(2)


def student_t95(dof):
    """The one-sided 95 % quantile of Student's t with `dof` degrees of freedom, by the
    Cornish-Fisher expansion in 1/dof (Abramowitz and Stegun 26.7.5): 1.8124 at 10 degrees of
    freedom and 1.6839 at 40, where the tables give 1.8125 and 1.6839."""
    z = CONFIDENCE_Z
    g1 = (z ** 3 + z) / 4
    g2 = (5 * z ** 5 + 16 * z ** 3 + 3 * z) / 96
    g3 = (3 * z ** 7 + 19 * z ** 5 + 17 * z ** 3 - 15 * z) / 384
    return z + g1 / dof + g2 / dof ** 2 + g3 / dof ** 3


def load(folder):
    path = folder.rstrip("/") + "/trials.jsonl"
    try:
        lines = open(path, encoding="utf-8").read().splitlines()
    except OSError as e:
        fail("%s: %s" % (path, e.strerror))
    trials = {}
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError as e:
            fail("%s:%d: not a JSON object (%s)" % (path, number, e.msg))
        if not isinstance(record, dict) or not isinstance(record.get("trial"), int):
            fail("%s:%d: a trial record needs a whole-number 'trial'" % (path, number))
        trials[record["trial"]] = record
    return path, trials


def robots_of(record):
    figures = record.get("figures") or {}
    names = set()
    for key in figures:
        parts = key.split(".")
        if len(parts) > 2 and parts[0] == "robots" and key.endswith(".rigid.after.rms"):
            names.add(parts[1])
    return names


# A trial that ran to its report but missed the scenario's acceptance targets exits 3
# (`twinbench run`; the study records it as failed): its figures are complete and count.
MISSED_TARGETS_EXIT = 3


def figure(record, robot, gauge):
    if record.get("status") != "ok" and record.get("exit_code") != MISSED_TARGETS_EXIT:
        return None
    value = (record.get("figures") or {}).get(FIGURE.format(robot=robot, gauge=gauge))
    return value if isinstance(value, (int, float)) and math.isfinite(value) else None


def meets_targets(record, robots):
    return all(figure(record, r, g) is not None and figure(record, r, g) <= TARGETS[g]
               for r in robots for g in GAUGES)


def ratio_of_means(pairs, rng):
    """mean(after) / mean(before) over (before, after) pairs, and its paired bootstrap one-sided
    95 % upper bound (the 95th percentile of the resampled ratios)."""
    def ratio(sample):
        return sum(a for _, a in sample) / sum(b for b, _ in sample)
    n = len(pairs)
    resampled = sorted(ratio([pairs[rng.randrange(n)] for _ in range(n)])
                       for _ in range(BOOTSTRAP_RESAMPLES))
    return ratio(pairs), resampled[int(0.95 * BOOTSTRAP_RESAMPLES)]


def main(argv):
    args = list(argv[1:])
    min_trials = 40
    if "--min-trials" in args:
        i = args.index("--min-trials")
        try:
            min_trials = int(args[i + 1])
        except (IndexError, ValueError):
            fail("--min-trials: expected a whole number")
        del args[i:i + 2]
    control = "--control" in args
    if control:
        args.remove("--control")
    if len(args) != 2:
        fail("usage: paired_verdict.py BEFORE_DIR AFTER_DIR [--min-trials N] [--control]")
    before_path, before = load(args[0])
    after_path, after = load(args[1])
    paired = sorted(set(before) & set(after))
    for t in paired:
        sb, sa = before[t].get("seeds"), after[t].get("seeds")
        if control and isinstance(sb, dict) and isinstance(sa, dict):
            sb, sa = sb.get("truth"), sa.get("truth")
        if sb != sa:
            fail("trial %d ran on other seeds: %s %s, %s %s (a paired study runs the same "
                 "trials)" % (t, before_path, json.dumps(sb), after_path, json.dumps(sa)))
    robots = sorted(set().union(*(robots_of(before[t]) for t in paired)) if paired else set())
    print("paired study: %s -> %s, %d paired trials (%d before, %d after), robots %s" %
          (before_path, after_path, len(paired), len(before), len(after),
           ", ".join(robots) or "none"))
    accepted = True
    if len(paired) < min_trials or not robots:
        print("too few paired trials: %d, the rule needs %d" % (len(paired), min_trials))
        accepted = False
    # 1. The ratio of the means and its bootstrap bound, per robot and gauge; the mean of the
    # per-trial ratios (Student's t bound) beside it, for information.
    rng = random.Random(42)
    for robot in robots:
        for gauge in GAUGES:
            pairs = [(figure(before[t], robot, gauge), figure(after[t], robot, gauge))
                     for t in paired]
            pairs = [(b, a) for b, a in pairs if b is not None and a is not None and b > 0]
            n = len(pairs)
            if n < 2:
                print("%s %s: %d pairs, no bound" % (robot, gauge, n))
                accepted = False
                continue
            value, bound = ratio_of_means(pairs, rng)
            ok = bound <= MAX_RATIO
            accepted &= ok
            ratios = [a / b for b, a in pairs]
            mean = sum(ratios) / n
            sd = math.sqrt(sum((r - mean) ** 2 for r in ratios) / (n - 1))
            print("%s %s: mean after / mean before %.4f over %d trials, 95 %% upper bound %.4f "
                  "(at most %.2f: %s); for information, the mean of the per-trial ratios %.4f, "
                  "bound %.4f" % (robot, gauge, value, n, bound, MAX_RATIO,
                                  "yes" if ok else "NO", mean,
                                  mean + student_t95(n - 1) * sd / math.sqrt(n)))
    # 2. The share of seeds meeting the targets.
    met_before = sum(meets_targets(before[t], robots) for t in paired)
    met_after = sum(meets_targets(after[t], robots) for t in paired)
    ok = met_after >= met_before
    accepted &= ok
    print("seeds meeting rigid <= %.1f and similarity <= %.1f mm: %d before, %d after "
          "(not fewer: %s)" % (TARGETS["rigid"], TARGETS["similarity"], met_before, met_after,
                               "yes" if ok else "NO"))
    # 3. No robot calibration newly above 0.6 mm rigid.
    crossed = []
    for t in paired:
        for robot in robots:
            b, a = figure(before[t], robot, "rigid"), figure(after[t], robot, "rigid")
            if b is not None and b <= CROSSING_MM and (a is None or a > CROSSING_MM):
                crossed.append("trial %d %s %.3f -> %s" %
                               (t, robot, b, "failed" if a is None else "%.3f" % a))
    accepted &= not crossed
    print("newly above %.1f mm rigid: %s" % (CROSSING_MM, "; ".join(crossed) or "none"))
    print("verdict: %s" % ("ACCEPTED" if accepted else "REJECTED"))
    return 0 if accepted else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
