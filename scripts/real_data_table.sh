#!/usr/bin/env bash
# Model discovery on the real Motoman laser-tracker files (../shared/data/motoman_leica/, see
# its README): each file identified with the other as its second session (`--validate`), with
# the defaults (the search ends on its tests; at most 10 effects), and the table of
# geometric, each discovery step and the black box, region-disjoint held out and on the second
# session, written to docs/results/real_data_discovery.md with the date, commit and commands.
#   scripts/real_data_table.sh [OUT]     OUT: the runs' folder (default: a temporary one)
set -euo pipefail
cd "$(dirname "$0")/.."
data=../shared/data/motoman_leica
[ -f "$data/right_arm_wide.csv" ] || { echo "error: $data/right_arm_wide.csv: not found" >&2; exit 2; }
out="${1:-$(mktemp -d /tmp/twinbench-real-data.XXXXXX)}"
mkdir -p "$out"
tb="${TWINBENCH:-build/bin/twinbench}"   # TWINBENCH: another build (e.g. a copy while rebuilding)
[ -x "$tb" ] || { echo "error: $tb: not built (scripts/build.sh)" >&2; exit 2; }
commands=()
run() {  # NAME FILE VALIDATE [ARGS...]
  local name=$1 file=$2 validate=$3
  shift 3
  local cmd="$tb identify --model models/motoman_sda10_right.yaml --measurements $data/$file --ignore-column q_E_rad --validate $data/$validate --out $out/$name $*"
  commands+=("$cmd")
  echo "running: $cmd" >&2
  local start=$(date +%s)
  $cmd >"$out/$name.log" 2>&1
  echo $(( $(date +%s) - start )) >"$out/$name.seconds"
}
run wide right_arm_wide.csv right_arm_cube.csv
run cube right_arm_cube.csv right_arm_wide.csv
python3 - "$out" "$(git rev-parse --short HEAD)" "$("$tb" --version)" "$(uname -m), $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo) GiB" "${commands[@]}" >docs/results/real_data_discovery.md <<'PY'
import json, sys, datetime
out, commit, version, machine, cmds = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5:]
print("# Model discovery on the real Motoman tracker files\n")
print(f"Written by `scripts/real_data_table.sh` on {datetime.date.today()} at commit {commit} ({version}), on {machine}.")
print("Region: the diagnosis's region-disjoint held-out RMS (5 k-means blocks of the points).")
print("Second session: the other file, the tracker pose refitted on a random half and the other")
print("half scored, mean +- sd over 20 halvings. Lengths in mm. Commands:\n")
for c in cmds: print(f"    {c}")
print()
def f(x): return "-" if x is None else f"{x:.4f}"
for name, title in [("wide", "right_arm_wide.csv, second session right_arm_cube.csv, defaults"),
                    ("cube", "right_arm_cube.csv, second session right_arm_wide.csv, defaults")]:
    r = json.load(open(f"{out}/{name}/report.json"))
    d = r["diagnosis"]; s = r["heldout"]["session"]; bb = d["black_box"]
    secs = open(f"{out}/{name}.seconds").read().strip()
    print(f"## {title}\n")
    print(f"Verdict `{d['verdict']}`; {secs} s on this machine.\n")
    print("| model | region held out | second session |")
    print("|---|---|---|")
    print(f"| nominal (tracker pose and reflector fitted) | | {f(s['nominal']['rms_mm'])} +- {f(s['nominal']['rms_sd_mm'])} |")
    print(f"| geometric | {f(d['heldout_rms_mm']['start'])} | {f(s['geometric']['rms_mm'])} +- {f(s['geometric']['rms_sd_mm'])} |")
    for st in d["steps"]:
        if not st["accepted"]: continue
        worse = " (worse than the step before)" if st.get("session_worse") else ""
        print(f"| step {st['step']}: + {st['accepted']} | {f(st['heldout_rms_after_mm'])} | {f(st.get('session_rms_mm'))} +- {f(st.get('session_rms_sd_mm'))}{worse} |")
    print(f"| black box on the geometric residual (comparator, never in the model) | {f(bb.get('heldout_rms_mm'))} | {f(bb.get('session_rms_mm'))} |")
    print()
PY
echo "wrote docs/results/real_data_discovery.md (runs in $out)" >&2
