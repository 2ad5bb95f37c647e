#!/usr/bin/env python3
"""scripts/paired_study_table.sh with two stand-in builds (scripts that write a study's
trials.jsonl on fixed seeds, the second build's figures a set factor of the first's): equal
figures give the verdict ACCEPTED and exit 0, 10 % worse ones REJECTED and exit 1; each run puts
its section above the ones before, which stay; fewer than 40 trials is bad input (exit 2) and
writes nothing; a control study (CONTROL=DIR) gets its own block whose verdict does not
count; a BEFORE:AFTER pair runs each build on its own scenario file and pairs trials by their
truth seed alone (a control of another estimator seed)."""
import os
import stat
import subprocess
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "paired_study_table.sh")

# A stand-in for `twinbench`: --version, and `study SCENARIO --trials N --out DIR --quiet`.
FAKE = r'''#!/usr/bin/env python3
import json, os, random, sys
FACTOR = %(factor)r
if sys.argv[1] == "--version":
    print("twinbench 0.1.0 (fake %(factor)r)"); sys.exit(0)
args = sys.argv[2:]
n = int(args[args.index("--trials") + 1]); out = args[args.index("--out") + 1]
estimator = 1000 if "reseeded" in args[0] else 3  # a control scenario: another estimator seed
os.makedirs(out, exist_ok=True)
rng = random.Random(5)
with open(os.path.join(out, "trials.jsonl"), "w") as f:
    for t in range(n):
        fig = {}
        for r in ("r1", "r2"):
            rigid = rng.uniform(0.05, 0.2) * FACTOR
            fig["robots.%%s.truth_position_error_mm.rigid.after.rms" %% r] = rigid
            fig["robots.%%s.truth_position_error_mm.similarity.after.rms" %% r] = 0.4 * rigid
        f.write(json.dumps({"trial": t, "status": "ok", "scenario_hash": "ab",
                            "seeds": {"truth": 3 + t, "estimator": estimator + t}, "figures": fig,
                            "run": {"wall_s": 10.0 * FACTOR,
                                    "timing": {"timing_s.planning_compute": 1.0}}}) + "\n")
'''


class PairedStudyTableTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.bins = {}
        for name, factor in (("same", 1.0), ("worse", 1.1)):
            path = os.path.join(self.dir.name, name)
            with open(path, "w") as f:
                f.write(FAKE % {"factor": factor})
            os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR)
            self.bins[name] = path
        self.doc = os.path.join(self.dir.name, "paired.md")

    def tearDown(self):
        self.dir.cleanup()

    def table(self, title, after, trials, out, scenarios=("paper_reinovo", "kuka_kr6r900"),
              **extra):
        env = dict(os.environ, PAIRED_DOC=self.doc, **extra)
        p = subprocess.run(["bash", SCRIPT, title, self.bins["same"], self.bins[after],
                            str(trials), os.path.join(self.dir.name, out)] + list(scenarios),
                           capture_output=True, text=True, env=env)
        return p.returncode, p.stdout + p.stderr

    def test_verdicts_and_sections_newest_first(self):
        code, out = self.table("lever A", "same", 40, "a")
        self.assertEqual(code, 0, out)
        code, out = self.table("lever B", "worse", 40, "b")
        self.assertEqual(code, 1, out)
        with open(self.doc) as f:
            text = f.read()
        self.assertTrue(text.startswith("# Paired studies"), text[:200])
        b, a = text.index("## lever B"), text.index("## lever A")
        self.assertLess(b, a)  # the newest section first, the older one kept
        self.assertEqual(text.count("### paper_reinovo"), 2)
        self.assertEqual(text.count("### kuka_kr6r900"), 2)
        self.assertIn("verdict: ACCEPTED", text[a:])
        self.assertIn("verdict: REJECTED", text[b:a])
        self.assertNotIn("ACCEPTED", text[b:a])
        self.assertIn("mean after / mean before 1.1000", text[b:a])
        self.assertIn("10 s a trial", text[a:])  # the stand-in's wall_s, 10 x its factor
        self.assertIn("11 s a trial", text[b:a])

    def test_a_control_is_tabled_and_does_not_count(self):
        code, out = self.table("lever B", "worse", 40, "b")  # its after study: a "worse" control
        self.assertEqual(code, 1, out)
        control = os.path.join(self.dir.name, "b", "paper_reinovo_after")
        code, out = self.table("lever A", "same", 40, "a", CONTROL=control,
                               CONTROL_NOTE="noise scaled")
        self.assertEqual(code, 0, out)  # the pair is accepted; the control's REJECTED does not count
        with open(self.doc) as f:
            text = f.read()
        a, b = text.index("## lever A"), text.index("## lever B")
        c = text.index("#### paper_reinovo: control (noise scaled)")
        self.assertLess(a, c)
        self.assertLess(c, text.index("### kuka_kr6r900", a))  # after the first scenario only
        self.assertEqual(text.count("#### "), 1)
        self.assertIn("verdict: REJECTED", text[c:b])
        self.assertIn("mean after / mean before 1.1000", text[c:b])
        # A control with fewer trials than the pair, or without its note, is refused.
        code, out = self.table("lever D", "same", 40, "a", CONTROL=self.dir.name,
                               CONTROL_NOTE="x")
        self.assertEqual(code, 2, out)
        code, out = self.table("lever D", "same", 40, "a", CONTROL=control)
        self.assertEqual(code, 2, out)
        self.assertIn("CONTROL_NOTE", out)

    def test_a_pair_of_scenario_files_pairs_trials_by_their_truth_seed(self):
        pair = "paper_reinovo:controls/paper_reinovo_reseeded"
        code, out = self.table("control", "same", 40, "d", scenarios=(pair,))
        self.assertEqual(code, 0, out)
        with open(self.doc) as f:
            text = f.read()
        self.assertIn("### paper_reinovo (before) against controls/paper_reinovo_reseeded (after)",
                      text)
        self.assertIn("scenarios/controls/paper_reinovo_reseeded.yaml --trials 40", text)
        self.assertIn("verdict: ACCEPTED", text)
        with open(os.path.join(self.dir.name, "d", "paper_reinovo_after", "trials.jsonl")) as f:
            self.assertIn('"estimator": 1000', f.read())  # the after study ran the second file
        # The same two studies as one scenario's pair: other estimator seeds are refused.
        verdict = subprocess.run(
            ["python3", os.path.join(ROOT, "scripts", "paired_verdict.py"),
             os.path.join(self.dir.name, "d", "paper_reinovo_before"),
             os.path.join(self.dir.name, "d", "paper_reinovo_after")],
            capture_output=True, text=True)
        self.assertEqual(verdict.returncode, 2, verdict.stdout + verdict.stderr)
        self.assertIn("ran on other seeds", verdict.stderr)
        # A missing file on either side, or a malformed pair, is bad input and writes nothing.
        for bad in ("paper_reinovo:controls/none", "paper_reinovo:", "a:b:c"):
            code, out = self.table("bad", "same", 40, "e", scenarios=(bad,))
            self.assertEqual(code, 2, bad + ": " + out)
            self.assertFalse(os.path.exists(os.path.join(self.dir.name, "e")), bad)

    def test_fewer_than_forty_trials_is_refused_and_writes_nothing(self):
        code, out = self.table("lever C", "same", 39, "c")
        self.assertEqual(code, 2, out)
        self.assertIn("at least 40", out)
        self.assertFalse(os.path.exists(self.doc))
        self.assertFalse(os.path.exists(os.path.join(self.dir.name, "c")))


if __name__ == "__main__":
    unittest.main()
