#!/usr/bin/env bash
# One command on a fresh Debian 12 machine: install what is missing, build, run the main job:
# the optical-axis self-calibration of both arms (Zhu et al. 2019) on the paper's scenario,
# closed loop on rendered images, scored against the twin's truth. Output: out/paper_reinovo/
# (report.json, report.html, measurements.csv, servo images). Another scenario: pass its path.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
scenario="${1:-scenarios/paper_reinovo.yaml}"
name="$(basename "${scenario}" .yaml)"
exec build/bin/twinbench run "${scenario}" --out "out/${name}"
