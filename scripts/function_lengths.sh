#!/usr/bin/env bash
# Lists the functions of C++ sources by length (lines from the signature to the closing brace,
# as universal-ctags finds them), longest first: `LENGTH FILE:LINE NAME`.
#   scripts/function_lengths.sh [--max N] [PATH ...]    (default PATH: calib bench sim)
# With --max N it prints only the functions longer than N lines and exits 1 when there is one
# (issue 43: at most 80 lines in calib/procedures, calib/diagnosis, bench/runs and
# bench/twinbench_main.cc). A function marked `// function-length: table` on the line above its
# signature (a table or registry: data, not steps) is listed but not counted.
set -euo pipefail
cd "$(dirname "$0")/.."
max=""
if [ "${1:-}" = "--max" ]; then
  [[ "${2:-}" =~ ^[0-9]+$ ]] || { echo "error: --max: expected a number of lines, got '${2:-}'" >&2; exit 2; }
  max="$2"
  shift 2
fi
[ $# -gt 0 ] || set -- calib bench sim
command -v ctags >/dev/null || { echo "error: universal-ctags is missing (scripts/install_deps.sh)" >&2; exit 2; }
over=0
while IFS=$'\t' read -r len where name table; do
  if [ -n "$max" ]; then
    [ "$len" -gt "$max" ] || continue
    if [ "$table" = "table" ]; then
      echo "$len $where $name (table, exempt)"
      continue
    fi
    over=$((over + 1))
  fi
  echo "$len $where $name"
done < <(
  find "$@" -name '*.cc' -o -name '*.h' | sort |
    xargs ctags --fields=+ne --kinds-c++=f -f - 2>/dev/null |
    awk -F'\t' '{
      line = ""; end = "";
      for (i = 4; i <= NF; i++) {
        if ($i ~ /^line:/) line = substr($i, 6);
        if ($i ~ /^end:/) end = substr($i, 5);
      }
      if (line != "" && end != "") print (end - line + 1) "\t" $2 ":" line "\t" $1;
    }' |
    while IFS=$'\t' read -r len where name; do
      file="${where%%:*}"; line="${where##*:}"; table=""
      if [ "$line" -gt 1 ] && sed -n "$((line - 1))p" "$file" | grep -q 'function-length: table'; then
        table="table"
      fi
      printf '%s\t%s\t%s\t%s\n' "$len" "$where" "$name" "$table"
    done | sort -t$'\t' -k1,1nr
)
if [ -n "$max" ] && [ "$over" -gt 0 ]; then
  echo "$over function(s) longer than $max lines" >&2
  exit 1
fi
