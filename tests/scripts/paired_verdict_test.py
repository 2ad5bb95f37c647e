#!/usr/bin/env python3
"""scripts/paired_verdict.py on synthetic paired studies whose verdict follows from how they
are built: the same figures after as before are accepted; every figure 10 % worse, a robot
newly above 0.6 mm rigid, a seed that stops meeting the targets and too few trials are each
rejected; trials of the same number on other seeds are bad input (exit 2), except that a
control (--control) may differ in its estimator seeds, never in its truth seeds. The rule's ratio of
the means is not biased where the mean of per-trial ratios (printed beside it) is."""
import json
import os
import random
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "paired_verdict.py")


def record(trial, r1_rigid, r2_rigid, similarity_share=0.4, seed_offset=0, status="ok",
           estimator_offset=0, exit_code=None):
    figures = {}
    for robot, rigid in (("r1", r1_rigid), ("r2", r2_rigid)):
        figures["robots.%s.truth_position_error_mm.rigid.after.rms" % robot] = rigid
        figures["robots.%s.truth_position_error_mm.similarity.after.rms" % robot] = (
            similarity_share * rigid)
    return {"trial": trial, "status": status, "scenario_hash": "0123456789abcdef",
            "seeds": {"truth": 7 + trial + seed_offset,
                      "estimator": 7 + trial + estimator_offset},
            "exit_code": (0 if status == "ok" else 1) if exit_code is None else exit_code,
            "figures": figures if status == "ok" or exit_code == 3 else {}}


def base_study(n=40):
    rng = random.Random(11)
    # rigid 0.05-0.2 mm, similarity 0.4 of it (0.02-0.08 mm): every seed meets the targets.
    return [record(t, rng.uniform(0.05, 0.2), rng.uniform(0.05, 0.2)) for t in range(n)]


class PairedVerdictTest(unittest.TestCase):
    def run_verdict(self, before, after, *extra):
        with tempfile.TemporaryDirectory() as d:
            for name, records in (("before", before), ("after", after)):
                os.mkdir(os.path.join(d, name))
                with open(os.path.join(d, name, "trials.jsonl"), "w") as f:
                    f.write("".join(json.dumps(r) + "\n" for r in records))
            p = subprocess.run([sys.executable, SCRIPT, os.path.join(d, "before"),
                                os.path.join(d, "after")] + list(extra),
                               capture_output=True, text=True)
            return p.returncode, p.stdout + p.stderr

    def test_the_same_figures_are_accepted(self):
        code, out = self.run_verdict(base_study(), base_study())
        self.assertEqual(code, 0, out)
        self.assertIn("verdict: ACCEPTED", out)
        self.assertIn("mean after / mean before 1.0000 over 40 trials, 95 % upper bound 1.0000",
                      out)

    def test_ten_percent_worse_everywhere_is_rejected(self):
        after = base_study()
        for r in after:
            for k in r["figures"]:
                r["figures"][k] *= 1.10
        code, out = self.run_verdict(base_study(), after)
        self.assertEqual(code, 1, out)
        self.assertIn("mean after / mean before 1.1000", out)
        self.assertIn("verdict: REJECTED", out)

    def test_three_percent_worse_with_scatter_is_accepted(self):
        # Ratios 1.03 +- 0.02 (uniform, sd 0.0115): the ratio of the means is about 1.03 and
        # its bound about 1.03 + 1.65 x 0.0115 / sqrt(40) = 1.033, below 1.05.
        rng = random.Random(3)
        after = base_study()
        for r in after:
            f = 1.03 + rng.uniform(-0.02, 0.02)
            for k in r["figures"]:
                r["figures"][k] *= f
        code, out = self.run_verdict(base_study(), after)
        self.assertEqual(code, 0, out)

    def test_errors_that_swap_between_builds_are_not_a_worse_mean(self):
        # Errors that swap between the builds: r1 0.1 and 0.2 mm before, 0.2 and 0.1 after. The
        # per-trial ratios are 2 and 0.5, mean 1.25, shown for information. The means are equal:
        # the ratio of the means is exactly 1, and its bootstrap bound (resampled pairs) is
        # above 1. r2 is the same in both: 1, bound 1.
        before = [record(t, 0.1 if t % 2 else 0.2, 0.15) for t in range(40)]
        after = [record(t, 0.2 if t % 2 else 0.1, 0.15) for t in range(40)]
        code, out = self.run_verdict(before, after)
        line = [l for l in out.splitlines() if l.startswith("r1 rigid:")]
        self.assertEqual(len(line), 1, out)
        self.assertIn("mean after / mean before 1.0000 over 40 trials", line[0])
        self.assertIn("the mean of the per-trial ratios 1.2500", line[0])
        bound = float(line[0].split("95 % upper bound ")[1].split(" ")[0])
        self.assertGreater(bound, 1.0)
        self.assertIn("r2 rigid: mean after / mean before 1.0000 over 40 trials, 95 % upper "
                      "bound 1.0000 (at most 1.05: yes)", out)
        # Half the pairs 2x, half 0.5x: the 40-trial bootstrap reaches past 1.05 (about 1.1),
        # so this scatter is still rejected.
        self.assertGreater(bound, 1.05)
        self.assertEqual(code, 1, out)

    def test_a_robot_newly_above_0_6_mm_is_rejected(self):
        before, after = base_study(), base_study()
        # 0.55 -> 0.65 mm in one trial: newly above 0.6 (and the target missed both times, so
        # the share of seeds meeting it does not change).
        for r, v in ((before[5], 0.55), (after[5], 0.65)):
            r["figures"]["robots.r2.truth_position_error_mm.rigid.after.rms"] = v
        code, out = self.run_verdict(before, after)
        self.assertEqual(code, 1, out)
        self.assertIn("trial 5 r2 0.550 -> 0.650", out)

    def test_a_seed_that_stops_meeting_the_targets_is_rejected(self):
        after = base_study()
        after[7] = record(7, 0.1, 0.1, status="failed")
        code, out = self.run_verdict(base_study(), after)
        self.assertEqual(code, 1, out)
        self.assertIn("40 before, 39 after (not fewer: NO)", out)

    def test_too_few_paired_trials_are_rejected(self):
        code, out = self.run_verdict(base_study(39), base_study(39))
        self.assertEqual(code, 1, out)
        self.assertIn("too few paired trials: 39, the rule needs 40", out)
        code, out = self.run_verdict(base_study(39), base_study(39), "--min-trials", "30")
        self.assertEqual(code, 0, out)

    def test_other_seeds_are_bad_input(self):
        after = base_study()
        after[3] = record(3, 0.1, 0.1, seed_offset=1)
        code, out = self.run_verdict(base_study(), after)
        self.assertEqual(code, 2, out)
        self.assertIn("trial 3 ran on other seeds", out)

    def test_a_trial_that_missed_its_scenario_targets_keeps_its_figures(self):
        # Exit 3: the run reached its report but missed an acceptance target of the scenario
        # (here r1 rigid 0.4 mm > 0.3); the study records it as failed, with its figures.
        after = base_study()
        after[5] = record(5, 0.4, 0.1, status="failed", exit_code=3)
        code, out = self.run_verdict(base_study(), after)
        self.assertIn("r1 rigid: mean after / mean before", out)
        self.assertIn("over 40 trials", out)  # trial 5 is in the ratio, not dropped
        self.assertIn("newly above 0.6 mm rigid: none", out)  # 0.4 mm crosses nothing
        self.assertIn("40 before, 39 after (not fewer: NO)", out)  # it misses the targets
        self.assertEqual(code, 1, out)
        # A trial that failed without its report (any other exit) has no figures: it crossed.
        after[5] = record(5, 0.1, 0.1, status="failed")
        code, out = self.run_verdict(base_study(), after)
        self.assertIn("trial 5 r1", out)
        self.assertIn("-> failed", out)

    def test_a_control_may_differ_in_its_estimator_seeds_only(self):
        reseeded = base_study()
        reseeded[3] = record(3, 0.1, 0.1, estimator_offset=1000)
        code, out = self.run_verdict(base_study(), reseeded)
        self.assertEqual(code, 2, out)  # not a control: every seed must match
        code, out = self.run_verdict(base_study(), reseeded, "--control")
        self.assertIn("40 paired trials", out)
        self.assertNotIn("other seeds", out)
        self.assertIn(code, (0, 1), out)
        other_truth = base_study()
        other_truth[3] = record(3, 0.1, 0.1, seed_offset=1)
        code, out = self.run_verdict(base_study(), other_truth, "--control")
        self.assertEqual(code, 2, out)
        self.assertIn("trial 3 ran on other seeds", out)


if __name__ == "__main__":
    unittest.main()
