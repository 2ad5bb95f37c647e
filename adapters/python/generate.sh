#!/usr/bin/env bash
# Generates the Python stubs of proto/twinbench/cell/v1/cell.proto and prints the folder to put
# on PYTHONPATH. The adapter does this by itself on first use; this is for a look at the stubs or
# for another program. Usage: adapters/python/generate.sh [OUT_DIR]
# (default OUT_DIR: $TWINBENCH_PY_GEN, else adapters/python/build/gen; see twinbench_cell/stubs.py).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
exec /usr/bin/python3 -m twinbench_cell.stubs "$@"
