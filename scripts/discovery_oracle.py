#!/usr/bin/env python3
"""The oracle control of a discovery row: could a test told the answer name the injected term?

Two subcommands (scripts/discovery_oracle.sh runs them; docs/explanation/discovery-statistics.md
says what the columns mean):

  given SCENARIO SPEC OUT_YAML
      Writes a copy of SCENARIO whose diagnosis is told the term: `candidates: [SPEC]` in its
      procedure section (calibration or tracker_calibration), every relative path that names a
      file beside SCENARIO made absolute. OUT_YAML must not exist.

  row [--alpha A] [--robot R] SCENARIO SEARCH_RUNS GIVEN_RUNS
      One markdown table row from two sets of trials of the same scenario (folders <t>/report.json
      of `twinbench run --trial t`; a study keeps no candidate lists): the search's own runs and
      the runs of the `given` copy. "Named" is the label (type, joint, orders); "type and
      joint" takes any order of the term on that joint. The given runs fit the one candidate beside the starting
      model. Its `visible_size_test` p value is the term's alone, with no multiplicity over
      other candidates: "p < alpha" counts the trials where a detector told type, joint and
      order in advance would call the term present. No search over many candidates names it in
      more trials than that. The same statistic of every candidate of the search's first fit
      (the screen's, or step 1's) ranks the term among them.

  level [--alpha A] [--robot R] SCENARIO RUNS
      One row on a scenario without an effect: of every candidate of the first fit in every
      trial, the share whose `visible_size_test` p is below alpha and below alpha / 10. A test
      at its level puts about alpha and alpha / 10 there; far fewer says the floor is too large
      (every test too cautious, the oracle's count too), far more that it is too small.

Exit 2 on bad input (a missing file or folder, no report, a report without that robot's
diagnosis, given runs without exactly one candidate, trials missing from either set).
"""
import argparse
import collections
import json
import os
import sys


def fail(message):
    print(f"discovery_oracle: {message}", file=sys.stderr)
    sys.exit(2)


# --- given --------------------------------------------------------------------------------

def absolute_paths(node, folder):
    """Every string that names an existing file or folder relative to `folder`, made absolute."""
    if isinstance(node, dict):
        return {k: absolute_paths(v, folder) for k, v in node.items()}
    if isinstance(node, list):
        return [absolute_paths(v, folder) for v in node]
    if isinstance(node, str) and node and not os.path.isabs(node) and ("/" in node or "." in node) \
            and os.path.exists(os.path.join(folder, node)):
        return os.path.normpath(os.path.join(folder, node))
    return node


def given(scenario, spec, out_yaml):
    import yaml  # python3-yaml (scripts/install_deps.sh)
    if not os.path.isfile(scenario):
        fail(f"{scenario}: no such scenario file")
    if os.path.exists(out_yaml):
        fail(f"{out_yaml}: exists; name a new file")
    with open(scenario) as f:
        doc = yaml.safe_load(f)
    body = doc.get("scenario") if isinstance(doc, dict) else None
    if not isinstance(body, dict):
        fail(f"{scenario}: no scenario: section")
    procedures = [k for k in ("calibration", "tracker_calibration") if isinstance(body.get(k), dict)]
    if len(procedures) != 1:
        fail(f"{scenario}: needs exactly one of calibration: or tracker_calibration:")
    section = body[procedures[0]]
    diagnosis = section.get("diagnosis") or {}
    if not isinstance(diagnosis, dict):
        fail(f"{scenario}: {procedures[0]}.diagnosis is not a map")
    diagnosis["candidates"] = [spec]
    section["diagnosis"] = diagnosis
    doc = absolute_paths(doc, os.path.dirname(os.path.abspath(scenario)))
    with open(out_yaml, "x") as f:
        f.write(f"# {os.path.basename(scenario)} with its diagnosis told the term {spec}\n"
                "# (written by scripts/discovery_oracle.py given; the oracle control)\n")
        yaml.safe_dump(doc, f, sort_keys=False)


# --- row ----------------------------------------------------------------------------------

def diagnoses(runs, robot):
    """{trial: diagnosis} of the report.json files under `runs`."""
    if not os.path.isdir(runs):
        fail(f"{runs}: no such folder")
    out = {}
    for name in os.listdir(runs):
        path = os.path.join(runs, name, "report.json")
        if not name.isdigit() or not os.path.isfile(path):
            continue
        try:
            with open(path) as f:
                report = json.load(f)
        except json.JSONDecodeError as e:
            fail(f"{path}: not JSON ({e})")
        if isinstance(report.get("diagnosis"), dict) and robot is None:
            out[int(name)] = report["diagnosis"]   # a tracker run's report: one robot
            continue
        robots = report.get("robots") or {}
        key = robot
        if key is None:
            diagnosed = sorted(r for r, v in robots.items() if isinstance(v, dict) and v.get("diagnosis"))
            if not diagnosed:
                fail(f"{path}: no robot has a diagnosis")
            key = "r2" if "r2" in diagnosed else diagnosed[0]
        entry = robots.get(key)
        if not isinstance(entry, dict) or not entry.get("diagnosis"):
            fail(f"{path}: robot {key} has no diagnosis")
        out[int(name)] = entry["diagnosis"]
    if not out:
        fail(f"{runs}: no trial folder with a report.json")
    return out


def first_candidates(d):
    """The candidates fitted beside the starting model: the screen's or step 1's."""
    return d.get("screened") or [c for c in d.get("candidates", []) if c.get("step") == 1]


def first_fit(d):
    """Those of first_candidates with a size test on what the data see."""
    return [c for c in first_candidates(d) if c.get("identifiable") and c.get("visible_size_test")]


def row(a):
    search = diagnoses(a.search_runs, a.robot)
    told = diagnoses(a.given_runs, a.robot)
    if sorted(search) != sorted(told):
        fail(f"the trials differ: {a.search_runs} has {sorted(search)}, {a.given_runs} has {sorted(told)}")
    labels = set()
    named = named_joint = named_any = significant = bonferroni = first = blind = 0
    instead = collections.Counter()
    for t in sorted(search):
        pool = first_candidates(told[t])
        if len(pool) != 1:
            fail(f"{a.given_runs}/{t}: the given run fitted {len(pool)} candidates, not 1")
        term = pool[0]
        labels.add(term["label"])
        added = search[t].get("effects_added", [])
        named += any(c["label"] == term["label"] for c in added)
        named_joint += any((c.get("term"), c.get("joint")) == (term.get("term"), term.get("joint"))
                           for c in added)
        named_any += any(c["label"] == term["label"] or term["label"] in c.get("indistinguishable_from", [])
                         for c in added)
        others = [c for c in first_fit(search[t]) if c["label"] != term["label"]]
        leader = min(others, key=lambda c: c["visible_size_test"]["p_value"]) if others else None
        if not term.get("identifiable") or not term.get("visible_size_test"):
            blind += 1
            if leader:
                instead[leader["label"]] += 1
            continue
        p = term["visible_size_test"]["p_value"]
        significant += p < a.alpha
        bonferroni += p < a.alpha / (len(others) + 1)
        if leader is None or p < leader["visible_size_test"]["p_value"]:
            first += 1
        else:
            instead[leader["label"]] += 1
    if len(labels) != 1:
        fail(f"{a.given_runs}: the given runs fitted different terms: {sorted(labels)}")
    n = len(search)
    top = instead.most_common(1)
    print(f"| {a.scenario} | {labels.pop()} | {n} | {named} of {n} | {named_joint} of {n} | {named_any} of {n} "
          f"| {significant} of {n} | {bonferroni} of {n} | {first} of {n} "
          f"| {f'{top[0][0]} ({top[0][1]})' if top else '-'} | {blind} of {n} |")


def level(a):
    runs = diagnoses(a.runs, a.robot)
    p = [c["visible_size_test"]["p_value"] for d in runs.values() for c in first_fit(d)]
    if not p:
        fail(f"{a.runs}: no candidate with a visible size test")
    below = sum(x < a.alpha for x in p)
    tenth = sum(x < a.alpha / 10 for x in p)
    print(f"| {a.scenario} | {len(runs)} | {len(p)} | {below} ({100.0 * below / len(p):.1f} %) "
          f"| {tenth} ({100.0 * tenth / len(p):.1f} %) |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    g = sub.add_parser("given", help="a copy of a scenario whose diagnosis is told the term")
    g.add_argument("scenario")
    g.add_argument("spec", help="TYPE[:JOINT[:ORDERS]], e.g. axis_wobble:1:2")
    g.add_argument("out_yaml")
    common = argparse.ArgumentParser(add_help=False)   # the options of row and level
    common.add_argument("--alpha", type=float, default=0.05, help="the level (default 0.05, the diagnosis' default)")
    common.add_argument("--robot", default=None, help="report.json robot key (default: r2 if diagnosed, else the one diagnosed)")
    r = sub.add_parser("row", parents=[common], help="one table row from the search's and the given runs")
    r.add_argument("scenario")
    r.add_argument("search_runs")
    r.add_argument("given_runs")
    v = sub.add_parser("level", parents=[common], help="the size test's rate below alpha on a scenario without an effect")
    v.add_argument("scenario")
    v.add_argument("runs")
    a = ap.parse_args()
    if a.command == "given":
        given(a.scenario, a.spec, a.out_yaml)
    else:
        if not 0.0 < a.alpha < 0.5:
            fail(f"--alpha must be in (0, 0.5), got {a.alpha}")
        row(a) if a.command == "row" else level(a)


if __name__ == "__main__":
    main()
