#!/usr/bin/env bash
# Runs the commands of the tutorials, so that a tutorial cannot go stale.
#   scripts/test_docs.sh [TWINBENCH] [TUTORIAL.md ...]
#       TWINBENCH: the binary to test (default build/bin/twinbench);
#       TUTORIAL.md: the pages to run (default docs/tutorials/*.md).
#
# The convention, for whoever writes a tutorial:
#   - A fenced block opened with exactly ```bash is run. Blocks opened with ```text, ```yaml,
#     ```sh or a bare ``` are shown to the reader and never run: use them for output, for file
#     contents and for commands that need something the test does not have.
#   - The commands are written as typed in a checkout's root, with `twinbench` for the program.
#     Each page runs in a fresh temporary folder that holds copies of models/ and scenarios/,
#     with `twinbench` on PATH as the binary under test; its blocks run one after another in
#     that folder, so a later block may read what an earlier one wrote (out/...).
#   - Each block runs with `bash -eo pipefail`: the test stops at the first command that
#     fails, naming the page and the block's line. A command expected to exit non-zero says so
#     in the block (`twinbench check bad.yaml || test $? -eq 2`).
#   - Keep every command well under a minute on 2 cores: the small scenarios
#     (scenarios/study_small.yaml, scenarios/tracker_reinovo.yaml with --no-diagnosis, a study
#     with --trials 2).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BIN="$(realpath "${1:-$ROOT/build/bin/twinbench}")"
shift || true
PAGES=("$@")
if [ ${#PAGES[@]} -eq 0 ]; then PAGES=("$ROOT"/docs/tutorials/*.md); fi
[ -x "$BIN" ] || { echo "error: $BIN: not an executable" >&2; exit 2; }

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
mkdir -p "$WORK/bin"
ln -s "$BIN" "$WORK/bin/twinbench"

blocks=0
for page in "${PAGES[@]}"; do
  name="$(basename "$page" .md)"
  dir="$WORK/$name"
  mkdir -p "$dir/blocks"
  cp -r "$ROOT/models" "$ROOT/scenarios" "$dir/"
  # Split the page into its ```bash blocks: blocks/NNN.sh, the first line a comment with the
  # line of the page where the block starts.
  awk -v out="$dir/blocks" '
    inblock && /^```[[:space:]]*$/ { inblock = 0; close(file); next }
    inblock { print > file; next }
    /^```bash[[:space:]]*$/ { n++; inblock = 1; file = sprintf("%s/%03d.sh", out, n);
                              printf "# line %d\n", NR > file; next }
    /^```/ { other = !other }' "$page"
  for block in "$dir"/blocks/*.sh; do
    [ -e "$block" ] || continue
    line="$(head -1 "$block" | sed 's/# line //')"
    echo "== $(basename "$page"):$line"
    sed 1d "$block" | sed 's/^/   $ /'
    start=$SECONDS
    if ! (cd "$dir" && PATH="$WORK/bin:$PATH" bash -eo pipefail "$block" > "$dir/block.log" 2>&1); then
      tail -n 40 "$dir/block.log" | cut -c1-400 | sed 's/^/   | /'
      echo "FAILED: $page, the block at line $line" >&2
      exit 1
    fi
    echo "   ok ($((SECONDS - start)) s)"
    blocks=$((blocks + 1))
  done
done
if [ "$blocks" -eq 0 ]; then
  echo "error: no \`\`\`bash blocks found in ${PAGES[*]}" >&2
  exit 1
fi
echo "$blocks tutorial blocks passed"
