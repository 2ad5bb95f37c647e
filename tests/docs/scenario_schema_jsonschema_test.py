#!/usr/bin/env python3
"""An independent check that schemas/scenario.schema.json is standard JSON Schema, as editors
use it: python3-jsonschema (not twinbench's own validator) validates every shipped scenario
(scenarios/**/*.yaml) against it, and refuses broken copies of them (a misspelled key, a wrong
type, a value out of its range, a newer format; inside the procedure sections calibration:,
handclasp:, tracker_calibration: and acceptance: too) at the key that is wrong.
Exit 77 (ctest's skip code) only when python3's jsonschema or yaml module is missing.
  tests/docs/scenario_schema_jsonschema_test.py"""
import copy
import json
import pathlib
import re
import sys

try:
    import jsonschema
    import yaml
except ImportError as e:
    print(f"skipped: {e} (Debian: python3-jsonschema python3-yaml)")
    sys.exit(77)

ROOT = pathlib.Path(__file__).resolve().parents[2]


class Loader(yaml.SafeLoader):
    """PyYAML reads YAML 1.1, whose floats need a dot and a signed exponent ("1e5" would be a
    string); YAML 1.2's core schema, as yaml-cpp and editors read it, takes them as numbers."""


Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?$|^[-+]?\.(inf|Inf|INF)$"
               r"|^\.(nan|NaN|NAN)$"),
    list("-+0123456789."))


def load(path):
    with open(path, encoding="utf-8") as f:
        return yaml.load(f, Loader=Loader)


def key_path(error):
    out = ""
    for p in error.absolute_path:
        out += f"[{p}]" if isinstance(p, int) else (("." if out else "") + p)
    return out


def main():
    schema = json.loads((ROOT / "schemas/scenario.schema.json").read_text(encoding="utf-8"))
    cls = jsonschema.validators.validator_for(schema)
    cls.check_schema(schema)
    validator = cls(schema)
    failures = []
    files = sorted((ROOT / "scenarios").rglob("*.yaml"))
    if len(files) < 30:
        failures.append(f"expected the 30+ shipped scenarios, found {len(files)}")
    for path in files:
        for error in validator.iter_errors(load(path)):
            failures.append(f"{path.relative_to(ROOT)}: {key_path(error)}: {error.message}")

    demo = load(ROOT / "scenarios/twin_demo.yaml")

    def broken(edit):
        doc = copy.deepcopy(demo)
        edit(doc["scenario"])
        return doc

    def misspell(s):
        s["camera"]["robott"] = s["camera"].pop("robot")

    def wrong_type(s):
        s["board"]["square_mm"] = "twenty"

    def out_of_range(s):
        s["camera"]["msaa"] = 3

    def newer(s):
        s["format"] = 3

    def second_rotation(s):
        s["camera"]["hand_eye"]["zyz_deg"] = [0, 0, 0]

    cases = [(misspell, "scenario.camera", "robott"),
             (wrong_type, "scenario.board.square_mm", "twenty"),
             (out_of_range, "scenario.camera.msaa", "3"),
             (newer, "scenario.format", "3"),
             (second_rotation, "scenario.camera.hand_eye", "")]
    # The procedure sections (issue 41): checked key by key, not only as maps.
    shipped = {name: load(ROOT / f"scenarios/{name}.yaml")
               for name in ("paper_reinovo", "tracker_reinovo", "gan2014_floor_floor")}

    def planning_key(s):
        s["calibration"]["planning"]["swarm_sise"] = s["calibration"]["planning"].pop("swarm_size")
    planning_key.scenario = "paper_reinovo"

    def tracker_poses(s):
        s["tracker_calibration"]["poses"] = "many"
    tracker_poses.scenario = "tracker_reinovo"

    def handclasp_key(s):
        s["handclasp"]["opertor_error_mm"] = 1
    handclasp_key.scenario = "gan2014_floor_floor"

    def criterion_figure(s):
        del s["acceptance"][0]["figure"]
    criterion_figure.scenario = "paper_reinovo"

    def points_word(s):
        s["handclasp"]["points"] = "many"
    points_word.scenario = "gan2014_floor_floor"

    def points_short(s):
        s["handclasp"]["points"] = [[0, 0, 0], [100, 0, 0], [0, 100, 0], [0, 0]]
    points_short.scenario = "gan2014_floor_floor"

    def criterion_bound(s):
        del s["acceptance"][0]["max"]
    criterion_bound.scenario = "paper_reinovo"

    def odd_squares(s):
        s["calibration"]["board_squares"] = [5, 4]
    odd_squares.scenario = "paper_reinovo"

    def alpha_bound(s):
        s["calibration"]["diagnosis"] = {"alpha": 0.5}
    alpha_bound.scenario = "paper_reinovo"

    procedure_cases = [(planning_key, "scenario.calibration.planning", "swarm_sise"),
                       (tracker_poses, "scenario.tracker_calibration.poses", "many"),
                       (handclasp_key, "scenario.handclasp", "opertor_error_mm"),
                       (criterion_figure, "scenario.acceptance[0]", "figure"),
                       (points_word, "scenario.handclasp.points", "many"),
                       (points_short, "scenario.handclasp.points", ""),
                       (criterion_bound, "scenario.acceptance[0]", ""),
                       (odd_squares, "scenario.calibration.board_squares[0]", "multiple of 2"),
                       (alpha_bound, "scenario.calibration.diagnosis.alpha", "0.5")]
    for edit, where, word in procedure_cases:
        doc = copy.deepcopy(shipped[edit.scenario])
        edit(doc["scenario"])
        errors = list(validator.iter_errors(doc))
        found = [e for e in errors if key_path(e) == where and word in e.message]
        if not found:
            failures.append(f"{edit.__name__}: expected an error at {where} naming '{word}', "
                            f"got {[(key_path(e), e.message) for e in errors]}")
    for edit, where, word in cases:
        errors = list(validator.iter_errors(broken(edit)))
        found = [e for e in errors if key_path(e) == where and word in e.message]
        if not found:
            failures.append(f"{edit.__name__}: expected an error at {where} naming '{word}', "
                            f"got {[(key_path(e), e.message) for e in errors]}")
    for f in failures:
        print("FAIL:", f)
    print(f"{len(files)} shipped scenarios valid, {len(cases) + len(procedure_cases)} broken "
          "ones refused"
          if not failures else f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
