#!/usr/bin/env bash
# The GL back ends (sim/render/gl_context.h), each in its own process as twinbench uses them:
#   - TWINBENCH_GL=osmesa and =egl render the paper scenario's first pose. Where EGL renders on
#     Mesa's software device (llvmpipe, as OSMesa does), the PNGs must be identical, byte for
#     byte: the same rasteriser behind two ways of making a context. On a GPU they are not
#     compared (another rasteriser; renderer_test measures accuracy against the projection).
#   - auto renders with OSMesa where EGL has no GPU, says why, and draws OSMesa's bytes (its
#     look at EGL's devices changed nothing); with EGL where there is a GPU.
#   - egl:99 and a misspelt value end with exit 2, name TWINBENCH_GL, and write nothing.
# Skipped (77) where there is no EGL at all (no libEGL, no device enumeration, no device).
# Usage: gl_backends_test.sh TWINBENCH SCENARIO
set -uo pipefail
TB=$1
SCENARIO=$2
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

render() {  # render NAME GL_VALUE: twinbench render into $TMP/NAME, stdout and stderr kept
  TWINBENCH_GL=$2 "$TB" render "$SCENARIO" --out "$TMP/$1" --poses 1 >"$TMP/$1.out" 2>"$TMP/$1.err"
}

render osmesa osmesa || fail "osmesa render failed: $(cat "$TMP/osmesa.err")"
grep -q "with osmesa (" "$TMP/osmesa.out" || fail "osmesa: $(cat "$TMP/osmesa.out")"

if ! render egl egl; then
  # Skipped only where EGL is absent (no libEGL, no device enumeration, no device at all); an
  # EGL that is there but cannot make a context (config, surfaceless, API) is a failure.
  if grep -q -E "TWINBENCH_GL=egl: (cannot open libEGL|EGL lacks device enumeration|EGL enumerates no device)" "$TMP/egl.err"; then
    echo "SKIP: no EGL here: $(cat "$TMP/egl.err")"
    exit 77
  fi
  fail "egl render failed: $(cat "$TMP/egl.err")"
fi
grep -q "with egl (" "$TMP/egl.out" || fail "egl: $(cat "$TMP/egl.out")"
ls "$TMP/osmesa"/*.png >/dev/null 2>&1 || fail "osmesa wrote no PNG"
if grep -q "with egl (llvmpipe" "$TMP/egl.out"; then
  for f in "$TMP/osmesa"/*.png; do
    cmp -s "$f" "$TMP/egl/$(basename "$f")" || fail "$(basename "$f") differs between OSMesa and EGL on llvmpipe"
  done
  echo "EGL on llvmpipe drew the same bytes as OSMesa: $(cd "$TMP/osmesa" && ls *.png | tr '\n' ' ')"
  gpu=0
else
  echo "EGL renders on a GPU: $(grep -o 'with egl (.*' "$TMP/egl.out"); its pixels are not compared"
  gpu=1
fi

render auto auto || fail "auto render failed: $(cat "$TMP/auto.err")"
if [ "$gpu" = 0 ]; then
  grep -q "with osmesa (.*EGL: no GPU device)" "$TMP/auto.out" || fail "auto without a GPU: $(cat "$TMP/auto.out")"
  # auto looked at EGL's devices before it fell back: that must leave OSMesa's pixels alone.
  for f in "$TMP/osmesa"/*.png; do
    cmp -s "$f" "$TMP/auto/$(basename "$f")" || fail "$(basename "$f") differs between osmesa and auto's OSMesa"
  done
else
  grep -q "with egl (" "$TMP/auto.out" || fail "auto with a GPU: $(cat "$TMP/auto.out")"
fi

for bad in egl:99 Egl; do
  render "bad_$bad" "$bad"
  rc=$?
  [ "$rc" = 2 ] || fail "TWINBENCH_GL=$bad: exit $rc, expected 2 ($(cat "$TMP/bad_$bad.err"))"
  grep -q "^error: TWINBENCH_GL=$bad: " "$TMP/bad_$bad.err" || fail "TWINBENCH_GL=$bad: $(cat "$TMP/bad_$bad.err")"
  [ ! -e "$TMP/bad_$bad" ] || fail "TWINBENCH_GL=$bad wrote $TMP/bad_$bad"
  echo "TWINBENCH_GL=$bad: exit 2, $(cat "$TMP/bad_$bad.err")"
done
echo "PASS"
