#!/usr/bin/env bash
# One command on a fresh Debian 12 machine: install what is missing, build, run the main job.
# Until the optical-axis calibration exists, the main job is the kinematic demo on the two
# robot models followed by renders of the default twin scenario into out/twin_demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
build/bin/twinbench demo
exec build/bin/twinbench render scenarios/twin_demo.yaml --out out/twin_demo "$@"
