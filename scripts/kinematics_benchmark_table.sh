#!/usr/bin/env bash
# Speed of the kinematics on each shipped arm (issue 42): `twinbench benchmark-kinematics` per
# model file (forward kinematics, the end-point Jacobian analytic and by autodiff, the inverse
# kinematics iterative and in closed form where the arm has a spherical wrist), written to
# docs/results/kinematics_benchmark.md with the date, commit, machine and commands.
#   scripts/kinematics_benchmark_table.sh      (needs a build: scripts/build.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
tb="${TWINBENCH:-build/bin/twinbench}"   # TWINBENCH: another build
[ -x "$tb" ] || { echo "error: $tb: not built (scripts/build.sh)" >&2; exit 2; }
out=docs/results/kinematics_benchmark.md
tmp="$(mktemp)"
trap 'rm -f "$tmp"' EXIT
{
  echo "# Kinematics benchmark on the shipped arms"
  echo
  echo "Written by \`scripts/kinematics_benchmark_table.sh\` on $(date -u '+%Y-%m-%d %H:%M UTC') at commit"
  echo "$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- calib bench || echo ' (with uncommitted changes)') ($("$tb" --version)), on $(uname -m), $(nproc) cores,"
  echo "$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo) GiB; wall-clock microseconds a call, one thread. The inverse kinematics"
  echo "solves the end poses of 256 random joint vectors inside the limits, the iterative solver"
  echo "from the next one's joints (far from the answer), the closed form giving all solutions."
  echo
  for m in models/reinovo_r2.yaml models/kuka_kr6r900sixx.urdf models/abb_irb2400.urdf \
           models/motoman_sda10_right.yaml; do
    links=()
    case "$m" in *.urdf) links=(--tip-link tool0) ;; esac
    echo "    $tb benchmark-kinematics $m ${links[*]+${links[*]}}"
    echo
    # The model loader's warnings (URDFs without masses) go to the terminal, not the table.
    "$tb" benchmark-kinematics "$m" ${links[@]+"${links[@]}"} | sed 's/^/    /'
    echo
  done
} >"$tmp"
mv "$tmp" "$out"
echo "wrote $out" >&2
