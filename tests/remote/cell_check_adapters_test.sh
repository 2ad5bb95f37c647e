#!/usr/bin/env bash
# Issue 40: `twinbench cell-check` on the twin served by `twinbench serve-cell --realtime`
# (scenarios/twin_demo.yaml: two robots and the camera) and on the Python fake adapter
# (adapters/python/fake_hardware.py) passes every check, motion included; the Python client
# (adapters/python/twinbench_cell/client.py) scripts the served twin (a move read back within
# 1 mrad, a frame of the camera's size); on each of the fake's three deliberately broken variants it
# exits 1 and names the check the variant breaks:
#   --break units    readings and limits in degrees  -> "units: limits in rad", "units: a move"
#   --break no-stop  a move runs on after its client went away -> "stop on disconnect"
#   --break clock    a clock that steps backwards    -> "monotonic clock"
# and no other check fails on them. Skipped (77) without Debian's python3-grpcio.
# Usage: cell_check_adapters_test.sh TWINBENCH_BINARY SOURCE_DIR
set -euo pipefail
bin=$1
src=$2
py=/usr/bin/python3
if ! "$py" -c "import grpc, google.protobuf" 2>/dev/null; then
  echo "skipped: /usr/bin/python3 has no grpc (python3-grpcio)"
  exit 77
fi
work=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT

# Starts the fake with extra arguments; prints its address once it listens.
start_fake() {
  local log=$work/fake_$RANDOM.log
  "$py" "$src/adapters/python/fake_hardware.py" --listen 127.0.0.1:0 --heartbeat-timeout 0.5 \
    "$@" >"$log" 2>&1 &
  pids+=($!)
  for _ in $(seq 1 100); do
    if grep -q "listening on" "$log"; then
      grep -o "127.0.0.1:[0-9]*" "$log" | head -1
      return 0
    fi
    sleep 0.1
  done
  echo "the fake adapter did not start: $(cat "$log")" >&2
  return 1
}

fail=0
# The served twin: every check passes, none skipped; then the Python client scripts it.
twin_log=$work/twin.log
"$bin" serve-cell "$src/scenarios/twin_demo.yaml" --listen 127.0.0.1:0 --realtime \
  --heartbeat-timeout 0.5 >"$twin_log" 2>&1 &
pids+=($!)
twin_addr=""
for _ in $(seq 1 300); do
  twin_addr=$(grep -o "127.0.0.1:[0-9]*" "$twin_log" | head -1 || true)
  [ -n "$twin_addr" ] && break
  sleep 0.1
done
if [ -z "$twin_addr" ]; then
  echo "FAILED: serve-cell did not start: $(cat "$twin_log")"; exit 1
fi
if ! "$bin" cell-check "grpc://$twin_addr" --allow-motion >"$work/twin.txt" 2>&1; then
  echo "FAILED: cell-check on the served twin exited non-zero:"; cat "$work/twin.txt"; fail=1
fi
if grep -qE "^(FAIL|SKIP) " "$work/twin.txt"; then
  echo "FAILED: a check failed or was skipped on the served twin:"; cat "$work/twin.txt"; fail=1
fi
if ! PYTHONPATH="$src/adapters/python" "$py" - "$twin_addr" >"$work/py_client.txt" 2>&1 <<'PY'
import sys
from twinbench_cell.client import RemoteCell
with RemoteCell(sys.argv[1]) as cell:
    d = cell.describe()
    assert len(d.robots) == 2, d
    q = cell.read_encoders(0)
    target = list(q)
    target[5] += 0.05
    result = cell.move_to(0, target)
    assert result.status == "SETTLED", result
    after = cell.read_encoders(0)
    assert max(abs(a - b) for a, b in zip(after, target)) < 1e-3, (after, target)
    width, height, rgb = cell.grab_image()
    assert (width, height) == (d.image_width_px, d.image_height_px), (width, height)
    assert len(rgb) == 3 * width * height
print("python client: moved, read back, grabbed", width, "x", height)
PY
then
  echo "FAILED: the Python client could not script the served twin:"; cat "$work/py_client.txt"
  fail=1
fi

# The good fake: every check passes, none skipped.
addr=$(start_fake)
if ! "$bin" cell-check "grpc://$addr" --allow-motion >"$work/good.txt" 2>&1; then
  echo "FAILED: cell-check on the fake adapter exited non-zero:"; cat "$work/good.txt"; fail=1
fi
if grep -qE "^(FAIL|SKIP) " "$work/good.txt"; then
  echo "FAILED: a check failed or was skipped on the fake adapter:"; cat "$work/good.txt"; fail=1
fi

# Without --allow-motion nothing is sent that could move a robot: the motion checks are
# skipped, and so are the malformed MoveTo and MountTarget probes (a server that does not check
# them might move); the rest pass.
if ! "$bin" cell-check "grpc://$addr" >"$work/still.txt" 2>&1; then
  echo "FAILED: cell-check without --allow-motion exited non-zero:"; cat "$work/still.txt"; fail=1
fi
if ! grep -qE "^PASS +malformed requests.*need --allow-motion" "$work/still.txt" ||
   ! grep -qE "^SKIP " "$work/still.txt" || grep -qE "^FAIL " "$work/still.txt"; then
  echo "FAILED: without --allow-motion, expected motion probes skipped:"; cat "$work/still.txt"
  fail=1
fi

# Each broken fake: exit 1, exactly the expected checks fail.
check_broken() {
  local variant=$1
  shift
  local out=$work/broken_$variant.txt rc=0
  local a
  a=$(start_fake --break "$variant")
  "$bin" cell-check "grpc://$a" --allow-motion >"$out" 2>&1 || rc=$?
  if [ "$rc" -ne 1 ]; then
    echo "FAILED: --break $variant: exit $rc, expected 1"; cat "$out"; fail=1
  fi
  for name in "$@"; do
    if ! grep -q "^FAIL  $name:" "$out"; then
      echo "FAILED: --break $variant: check '$name' did not fail"; cat "$out"; fail=1
    fi
  done
  local n_failed
  n_failed=$(grep -c "^FAIL " "$out" || true)
  if [ "$n_failed" -ne "$#" ]; then
    echo "FAILED: --break $variant: $n_failed checks failed, expected $# ($*)"
    cat "$out"; fail=1
  fi
}
check_broken units "units: limits in rad" "units: a move"
check_broken no-stop "stop on disconnect"
check_broken clock "monotonic clock"

if [ "$fail" -ne 0 ]; then exit 1; fi
echo "cell-check: the served twin and the fake adapter pass; the three broken ones fail at their checks"
