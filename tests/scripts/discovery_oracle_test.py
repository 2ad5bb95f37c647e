#!/usr/bin/env python3
"""scripts/discovery_oracle.{py,sh}, the oracle control of discovery rows, on reports whose counts
follow from how they are built.

- `given` writes a copy of a shipped scenario told one candidate, its model paths absolute, and
  refuses an existing output and a file without a procedure section (exit 2).
- `row` counts, over three built trials: named by the search (by label, and by type and joint),
  named or indistinguishable, the
  told term's own p below 0.05, below 0.05 / m, ranked first, and who ranked first instead; two
  sets of runs over other trials, and given runs with more than one candidate, are bad input.
- `level` counts the share of every first fit's candidates below 0.05 and 0.005.
- The shell script, with a stand-in twinbench that writes such reports, runs both sets (and a
  clean scenario's) and puts its section at the top of the doc; it refuses a folder it did not write.
The parts that read YAML are skipped without python3-yaml (scripts/install_deps.sh installs it)."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PY = os.path.join(ROOT, "scripts", "discovery_oracle.py")
SH = os.path.join(ROOT, "scripts", "discovery_oracle.sh")
TERM = "lateral_compliance (joint 1)"
OTHER = "transmission_error (joint 2, order 1)"
try:
    import yaml
except ImportError:
    yaml = None


KIND = {TERM: ("lateral_compliance", 1), OTHER: ("transmission_error", 2)}


def candidate(label, p, step=0):
    return {"label": label, "term": KIND[label][0], "joint": KIND[label][1], "step": step,
            "identifiable": True, "visible_size_test": {"statistic": 1.0, "dof": 1, "p_value": p}}


def write_report(folder, screened=None, candidates=None, added=None):
    os.makedirs(folder)
    diagnosis = {"screened": screened or [], "candidates": candidates or [],
                 "effects_added": added or []}
    with open(os.path.join(folder, "report.json"), "w") as f:
        json.dump({"robots": {"r1": {"diagnosis": None}, "r2": {"diagnosis": diagnosis}}}, f)


# Trial: (the told term's p, the other candidate's p, what the search added).
# 0: named; p 0.001 < 0.05 and < 0.05 / 2; ranked first.
# 1: another term added, the told one named indistinguishable from it, and a term of the same
#    type and joint (another order) added; p 0.03 < 0.05 only; the other candidate first.
# 2: nothing added; p 0.2; the other candidate first.
TRIALS = [
    (0.001, 0.01, [{"label": TERM, "term": "lateral_compliance", "joint": 1,
                    "indistinguishable_from": []}]),
    (0.03, 0.001, [{"label": OTHER, "term": "transmission_error", "joint": 2,
                    "indistinguishable_from": [TERM]},
                   {"label": "lateral_compliance (joint 1, other)", "term": "lateral_compliance",
                    "joint": 1}]),
    (0.2, 0.04, []),
]
EXPECTED_ROW = (f"| s | {TERM} | 3 | 1 of 3 | 2 of 3 | 2 of 3 | 2 of 3 | 1 of 3 | 1 of 3 | {OTHER} (2) | 0 of 3 |")

LEVEL_ROW = "| CLEAN | 3 | 6 | 5 (83.3 %) | 2 (33.3 %) |"


def build_runs(root):
    search, given = os.path.join(root, "search"), os.path.join(root, "given")
    for t, (p_term, p_other, added) in enumerate(TRIALS):
        # the search: its first fit's candidates (screened where nothing was searched)
        pool = [candidate(TERM, p_term), candidate(OTHER, p_other)]
        if added:
            write_report(os.path.join(search, str(t)), candidates=[dict(c, step=1) for c in pool], added=added)
        else:
            write_report(os.path.join(search, str(t)), screened=pool)
        write_report(os.path.join(given, str(t)), screened=[candidate(TERM, p_term)])
    return search, given


def run(*args, env=None):
    return subprocess.run(list(args), capture_output=True, text=True, env=env)


@unittest.skipIf(yaml is None, "python3-yaml")
class GivenTest(unittest.TestCase):
    def test_a_copy_told_one_candidate_with_absolute_model_paths(self):
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "given.yaml")
            src = os.path.join(ROOT, "scenarios", "discovery", "optical_axis_wobble_j1.yaml")
            r = run(sys.executable, PY, "given", src, "axis_wobble:1:2", out)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(out) as f:
                doc = yaml.safe_load(f)
            self.assertEqual(doc["scenario"]["calibration"]["diagnosis"]["candidates"], ["axis_wobble:1:2"])
            for robot in doc["scenario"]["robots"]:
                self.assertTrue(os.path.isabs(robot["model"]), robot["model"])
                self.assertTrue(os.path.isfile(robot["model"]), robot["model"])
            with open(src) as f:
                original = yaml.safe_load(f)["scenario"]
            self.assertEqual(doc["scenario"]["seeds"], original["seeds"])
            self.assertEqual(doc["scenario"]["effects"], original["effects"])
            # an existing output is never overwritten
            r = run(sys.executable, PY, "given", src, "axis_wobble:1:2", out)
            self.assertEqual(r.returncode, 2)
            self.assertIn("exists", r.stderr)

    def test_a_file_without_a_procedure_section_is_refused(self):
        with tempfile.TemporaryDirectory() as d:
            src = os.path.join(d, "s.yaml")
            with open(src, "w") as f:
                f.write("scenario:\n  name: x\n")
            r = run(sys.executable, PY, "given", src, "axis_wobble:1:2", os.path.join(d, "o.yaml"))
            self.assertEqual(r.returncode, 2)
            self.assertIn("calibration", r.stderr)
            self.assertFalse(os.path.exists(os.path.join(d, "o.yaml")))


class RowTest(unittest.TestCase):
    def assert_row(self, search, given):
        r = run(sys.executable, PY, "row", "s", search, given)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.strip(), EXPECTED_ROW)

    def test_the_counts_follow_from_the_built_trials(self):
        with tempfile.TemporaryDirectory() as d:
            self.assert_row(*build_runs(d))

    def test_the_level_row_counts_every_candidate_of_every_first_fit(self):
        with tempfile.TemporaryDirectory() as d:
            search, _ = build_runs(d)
            r = run(sys.executable, PY, "level", "s", search)
            self.assertEqual(r.returncode, 0, r.stderr)
            # p values 0.001 0.01 | 0.03 0.001 | 0.2 0.04: five below 0.05, two below 0.005
            self.assertEqual(r.stdout.strip(), LEVEL_ROW.replace("CLEAN", "s"))

    def test_a_tracker_report_has_its_one_diagnosis_at_the_top(self):
        with tempfile.TemporaryDirectory() as d:
            search, given = build_runs(d)
            for runs in (search, given):
                for t in os.listdir(runs):
                    path = os.path.join(runs, t, "report.json")
                    with open(path) as f:
                        report = json.load(f)
                    with open(path, "w") as f:
                        json.dump({"diagnosis": report["robots"]["r2"]["diagnosis"]}, f)
            self.assert_row(search, given)

    def test_other_trials_and_more_than_one_told_candidate_are_bad_input(self):
        with tempfile.TemporaryDirectory() as d:
            search, given = build_runs(d)
            write_report(os.path.join(search, "3"), screened=[candidate(TERM, 0.5)])
            r = run(sys.executable, PY, "row", "s", search, given)
            self.assertEqual(r.returncode, 2)
            self.assertIn("trials differ", r.stderr)
        with tempfile.TemporaryDirectory() as d:
            search, given = build_runs(d)
            with open(os.path.join(given, "1", "report.json")) as f:
                report = json.load(f)
            report["robots"]["r2"]["diagnosis"]["screened"].append(candidate(OTHER, 0.1))
            with open(os.path.join(given, "1", "report.json"), "w") as f:
                json.dump(report, f)
            r = run(sys.executable, PY, "row", "s", search, given)
            self.assertEqual(r.returncode, 2)
            self.assertIn("2 candidates", r.stderr)


STAND_IN = r'''#!/usr/bin/env python3
# A stand-in twinbench: `--version`, and `run FILE --trial T --out DIR ...` writing the trial's
# report as the test built it (the told copy fits the term alone).
import json, os, sys
if sys.argv[1] == "--version":
    print("twinbench stand-in"); sys.exit(0)
trials = json.loads(os.environ["ORACLE_TRIALS"])
a = sys.argv
file, t, out = a[2], int(a[a.index("--trial") + 1]), a[a.index("--out") + 1]
p_term, p_other, added = trials[t]
told = "given" in os.path.basename(file)
pool = [{"label": "%s", "term": "lateral_compliance", "joint": 1, "step": 0, "identifiable": True,
         "visible_size_test": {"p_value": p_term}}]
if not told:
    pool.append({"label": "%s", "term": "transmission_error", "joint": 2, "step": 0, "identifiable": True,
                 "visible_size_test": {"p_value": p_other}})
os.makedirs(out)
json.dump({"robots": {"r2": {"diagnosis": {"screened": pool, "candidates": [],
           "effects_added": [] if told else added}}}}, open(os.path.join(out, "report.json"), "w"))
''' % (TERM, OTHER)


@unittest.skipIf(yaml is None, "python3-yaml")
class ScriptTest(unittest.TestCase):
    def test_the_script_runs_both_sets_and_writes_its_section_first(self):
        with tempfile.TemporaryDirectory() as d:
            bin_path = os.path.join(d, "twinbench")
            with open(bin_path, "w") as f:
                f.write(STAND_IN)
            os.chmod(bin_path, 0o755)
            doc = os.path.join(d, "doc.md")
            with open(doc, "w") as f:
                f.write("# Title\n\nIntro.\n\n## Run of earlier\n\nold\n")
            env = dict(os.environ, TWINBENCH=bin_path, ORACLE_DOC=doc, JOBS="1",
                       ORACLE_TRIALS=json.dumps(TRIALS), CLEAN="optical_clean")
            out = os.path.join(d, "out")
            r = run("bash", SH, "3", out, "optical_base_compliance=lateral_compliance:1", env=env)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(doc) as f:
                text = f.read()
            self.assertTrue(text.startswith("# Title\n\nIntro.\n\n## Run of "), text[:80])
            self.assertLess(text.index("optical_base_compliance | " + TERM), text.index("## Run of earlier"))
            self.assertIn(EXPECTED_ROW.replace("| s |", "| optical_base_compliance |"), text)
            self.assertIn(LEVEL_ROW.replace("CLEAN", "optical_clean"), text)
            # a folder the script did not write is refused, and nothing is written
            other = os.path.join(d, "mine")
            os.makedirs(other)
            r = run("bash", SH, "3", other, "optical_base_compliance=lateral_compliance:1", env=env)
            self.assertEqual(r.returncode, 2)
            self.assertEqual(os.listdir(other), [])
            # a scenario that is not there
            r = run("bash", SH, "3", out, "nonesuch=lateral_compliance:1", env=env)
            self.assertEqual(r.returncode, 2)
            self.assertIn("nonesuch", r.stderr)


if __name__ == "__main__":
    unittest.main()
