#!/usr/bin/env bash
# The remote-cell benchmark (docs/results/remote_cell.md, issue 40): the wall time of
# `twinbench run SCENARIO` in process against the same run over the cell protocol, with the twin
# served on loopback over TLS (`twinbench serve-cell`, throwaway certificates made with openssl,
# client certificates required), alternating in-process and remote runs REPEATS times each.
# The remote figure is the run's own wall time (the server is started before the clock runs).
# It also checks that the two reports agree (report.json without its timing fields, by
# scripts/report_equal.py).
# Usage: scripts/benchmark_remote.sh [SCENARIO] [REPEATS] [OUT_DIR] [TABLE]
#   defaults: scenarios/paper_reinovo.yaml, 3, out/benchmark_remote, docs/results/remote_cell.md.
#   Needs a build (scripts/build.sh), openssl and python3. TWINBENCH: another binary.
set -euo pipefail
cd "$(dirname "$0")/.."
SCENARIO="${1:-scenarios/paper_reinovo.yaml}"
REPEATS="${2:-3}"
OUT="${3:-out/benchmark_remote}"
TABLE="${4:-docs/results/remote_cell.md}"
BIN="${TWINBENCH:-build/bin/twinbench}"
[ -x "$BIN" ] || { echo "benchmark_remote: build first (scripts/build.sh)" >&2; exit 2; }
command -v openssl >/dev/null || { echo "benchmark_remote: needs openssl" >&2; exit 2; }
mkdir -p "$OUT" "$(dirname "$TABLE")"
COMMIT="$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- calib sim bench remote || echo ' (with uncommitted changes)')"
STARTED="$(date -u '+%Y-%m-%d %H:%M UTC')"

# Throwaway PKI: a CA, a server certificate for 127.0.0.1, a client certificate.
PKI="$OUT/pki"
rm -rf "$PKI" && mkdir -p "$PKI"
(
  cd "$PKI"
  openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -keyout ca.key \
    -out ca.crt -days 2 -subj "/CN=benchmark CA" 2>/dev/null
  for who in server client; do
    openssl req -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -keyout "$who.key" \
      -out "$who.csr" -subj "/CN=$who" 2>/dev/null
  done
  printf 'subjectAltName=IP:127.0.0.1\n' > server.ext
  openssl x509 -req -in server.csr -CA ca.crt -CAkey ca.key -CAcreateserial -out server.crt \
    -days 2 -extfile server.ext 2>/dev/null
  openssl x509 -req -in client.csr -CA ca.crt -CAkey ca.key -CAcreateserial -out client.crt \
    -days 2 2>/dev/null
)

SERVER_PID=""
trap '[ -n "$SERVER_PID" ] && kill "$SERVER_PID" 2>/dev/null || true' EXIT
start_server() {
  local log="$OUT/server.log"
  "$BIN" serve-cell "$SCENARIO" --listen 127.0.0.1:0 --tls-cert "$PKI/server.crt" \
    --tls-key "$PKI/server.key" --client-ca "$PKI/ca.crt" > "$log" 2>&1 &
  SERVER_PID=$!
  for _ in $(seq 1 300); do
    ADDR=$(grep -o '127.0.0.1:[0-9]*' "$log" | head -1 || true)
    [ -n "$ADDR" ] && return 0
    sleep 0.1
  done
  echo "benchmark_remote: serve-cell did not start: $(cat "$log")" >&2
  exit 1
}
stop_server() {
  kill "$SERVER_PID" 2>/dev/null || true
  wait "$SERVER_PID" 2>/dev/null || true
  SERVER_PID=""
}

ROWS=""
local_sum=0
remote_sum=0
for ((i = 0; i < REPEATS; ++i)); do
  rm -rf "$OUT/local.$i" "$OUT/remote.$i"
  t0=$(date +%s.%N)
  "$BIN" run "$SCENARIO" --out "$OUT/local.$i" --quiet > "$OUT/local.$i.log" 2>&1 || true
  t1=$(date +%s.%N)
  start_server
  t2=$(date +%s.%N)
  "$BIN" run "$SCENARIO" --out "$OUT/remote.$i" --quiet --cell "grpc://$ADDR" \
    --cell-ca "$PKI/ca.crt" --cell-cert "$PKI/client.crt" --cell-key "$PKI/client.key" \
    > "$OUT/remote.$i.log" 2>&1 || true
  t3=$(date +%s.%N)
  stop_server
  local_s=$(echo "$t1 - $t0" | bc)
  remote_s=$(echo "$t3 - $t2" | bc)
  same=$(python3 scripts/report_equal.py "$OUT/local.$i/report.json" "$OUT/remote.$i/report.json" \
           > "$OUT/equal.$i.txt" 2>&1 && echo yes || echo "no ($(head -1 "$OUT/equal.$i.txt"))")
  ROWS+="| $i | $(printf '%.1f' "$local_s") | $(printf '%.1f' "$remote_s") | $(printf '%+.1f' "$(echo "100 * ($remote_s - $local_s) / $local_s" | bc -l)") % | $same |"$'\n'
  local_sum=$(echo "$local_sum + $local_s" | bc)
  remote_sum=$(echo "$remote_sum + $remote_s" | bc)
done
{
  printf '# The remote cell against the in-process twin: wall time\n\n'
  printf -- '- date: %s\n- commit: %s\n' "$STARTED" "$COMMIT"
  printf -- '- machine: %s, %s cores, %s GiB; client and server on the same machine (loopback)\n' \
    "$(uname -m)" "$(nproc)" "$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo)"
  printf -- '- command: `scripts/benchmark_remote.sh %s %s %s %s`\n' "$SCENARIO" "$REPEATS" "$OUT" "$TABLE"
  printf -- '- in process: `twinbench run %s --quiet`; remote: `twinbench serve-cell` (TLS, client certificates required) and `twinbench run --cell grpc://127.0.0.1:PORT` with the client certificate; runs alternate; the remote time is the client'"'"'s wall time\n' "$SCENARIO"
  printf -- '- same report: report.json equal but for its timing fields (scripts/report_equal.py)\n\n'
  printf '| repeat | in process [s] | remote [s] | remote vs in process | same report |\n'
  printf '|---|---|---|---|---|\n'
  printf '%s' "$ROWS"
  printf '| mean | %.1f | %.1f | %+.1f %% | |\n' "$(echo "$local_sum / $REPEATS" | bc -l)" \
    "$(echo "$remote_sum / $REPEATS" | bc -l)" \
    "$(echo "100 * ($remote_sum - $local_sum) / $local_sum" | bc -l)"
} > "$TABLE"
cat "$TABLE"
