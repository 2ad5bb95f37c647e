#!/usr/bin/env python3
"""Two report.json files equal but for their timing (issue 40: a remote run, a replay and an
in-process run of the same scenario and trial write the same report). The keys that hold
wall-clock time, as bench/report/trial_record.cc sorts them (timing_s, time_s, *_time_s,
from_plan_store), are left out at any depth; everything else must be equal, numbers bit for bit
(json reads them back exactly as written).
Usage: report_equal.py A.json B.json   exit 0 equal, 1 different (the first differences printed),
2 unreadable input."""
import json
import sys


def is_timing(key):
    return key in ("timing_s", "time_s", "from_plan_store") or (
        len(key) > 7 and key.endswith("_time_s"))


def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items() if not is_timing(k)}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x


def differences(a, b, path="", out=None, limit=10):
    out = [] if out is None else out
    if len(out) >= limit:
        return out
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                out.append(f"{path}.{k}: only in {'B' if k not in a else 'A'}")
            else:
                differences(a[k], b[k], f"{path}.{k}", out, limit)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{path}: {len(a)} entries against {len(b)}")
        for i, (u, v) in enumerate(zip(a, b)):
            differences(u, v, f"{path}[{i}]", out, limit)
    elif a != b and not (a != a and b != b):  # NaN equals NaN here
        out.append(f"{path}: {a!r} against {b!r}")
    return out


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    try:
        a, b = (strip(json.load(open(p))) for p in sys.argv[1:])
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    diff = differences(a, b)
    for d in diff:
        print(d)
    return 1 if diff else 0


if __name__ == "__main__":
    sys.exit(main())
