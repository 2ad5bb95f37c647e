#!/usr/bin/env bash
# Installs the Debian 12 packages the project builds and tests with (Slurm and munge for the
# Slurm harness test), only those missing (idempotent and quiet when everything is there). Needs
# root or sudo when something is missing.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libceres-dev libopencv-dev
  libblas3 liblapack3   # the reference BLAS / LAPACK every program links by DT_RPATH (cmake/ReferenceBlas.cmake)
  libmujoco-dev libqhull-dev libosmesa6-dev
  libegl-dev libegl-mesa0   # the EGL render path (sim/render/gl_context.h): headers; Mesa's EGL for its test
  liburdfdom-dev liburdfdom-headers-dev libconsole-bridge-dev
  libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev
  slurmctld slurmd slurm-client munge
  time jq   # jq: scripts/discovery_table.sh
  python3-jsonschema python3-yaml  # tests/docs/scenario_schema_jsonschema_test.py (skipped without)
  ccache           # scripts/build.sh and test_sanitizers.sh compile through it (cmake/Ccache.cmake)
  universal-ctags  # scripts/function_lengths.sh
  dpkg-dev file    # the packaging test: cpack -G DEB derives Depends with dpkg-shlibdeps
  # issue 40, the remote cell: gRPC protocol (proto/twinbench/cell/v1), C++ server and client,
  # and the Python adapter (adapters/python/)
  python3-grpcio python3-protobuf protobuf-compiler protobuf-compiler-grpc
  libgrpc++-dev libprotobuf-dev
  openssl          # the remote tests make throwaway TLS certificates (skipped without)
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "Installing missing packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "error: need root or sudo to install ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "Installed: ${missing[*]}"
