#!/usr/bin/env bash
# Issue 41, item 5: the Debian package of this build tree, installed into a temporary root (no
# root rights: dpkg-deb -x), must work there.
#   1. cpack -G DEB builds the .deb (name, version, maintainer, dependencies checked);
#   2. the installed twinbench prints its --version, runs `check` on an installed scenario and
#      finds its installed data (models/) from its own location, with a clear error (exit 2)
#      when that data is missing, and TWINBENCH_DATA_DIR overriding it;
#   3. a program outside the project (tests/packaging/consumer) configures and builds against
#      the exported CMake package (CMAKE_PREFIX_PATH=<root>/usr), links twinbench::calib, and
#      its forward kinematics of an installed model agree with the installed twinbench's.
# Any failing step fails the test.
#   packaging_test.sh BUILD_DIR SOURCE_DIR PROJECT_VERSION
set -euo pipefail

build=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
version=$3
tmp=$(mktemp -d "${TMPDIR:-/tmp}/twinbench_packaging.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

fail() { echo "FAIL: $*" >&2; exit 1; }
step() { echo "== $*"; }
# run LOG CMD...: runs CMD with its output in LOG, shown when it fails.
run() {
  local log=$1; shift
  local rc=0
  "$@" >"$log" 2>&1 || rc=$?
  if [ $rc -ne 0 ]; then
    cat "$log" >&2
    fail "$* (exit status $rc)"
  fi
}
for tool in cpack dpkg-deb dpkg-shlibdeps file cmake; do
  command -v "$tool" >/dev/null ||
    fail "$tool not found (Debian packages cmake, dpkg-dev, file: scripts/install_deps.sh)"
done

step "cpack -G DEB in $build"
run "$tmp/cpack.log" cpack -G DEB --config "$build/CPackConfig.cmake" -B "$tmp/pkg"
debs=("$tmp"/pkg/*.deb)
[ ${#debs[@]} -eq 1 ] && [ -f "${debs[0]}" ] || fail "expected one .deb in $tmp/pkg: ${debs[*]}"
deb=${debs[0]}
field() { dpkg-deb --field "$deb" "$1"; }
[ "$(field Package)" = twinbench ] || fail "Package is '$(field Package)'"
[[ "$(field Version)" == "$version"-* ]] || fail "Version '$(field Version)' is not $version-*"
[[ "$(field Maintainer)" == *"<"*"@"*">" ]] || fail "Maintainer '$(field Maintainer)'"
[ -n "$(field Description)" ] || fail "no Description"
depends=$(field Depends)
for lib in libc6 libmujoco libopencv-core libyaml-cpp liburdfdom libosmesa6 libblas3 liblapack3; do
  [[ "$depends" == *"$lib"* ]] || fail "Depends lacks $lib: $depends"
done
echo "$(basename "$deb"): Depends: $depends"

step "dpkg-deb -x into $tmp/root"
dpkg-deb -x "$deb" "$tmp/root"
usr=$tmp/root/usr
tb=$usr/bin/twinbench
data=$usr/share/twinbench
[ -x "$tb" ] || fail "no executable $tb in the package"
for f in "$data/models/reinovo_r1.yaml" "$data/scenarios/paper_reinovo.yaml" \
         "$usr/lib/cmake/twinbench/twinbenchConfig.cmake" "$usr/include/twinbench/calib/kinematics/forward_kinematics.h"; do
  [ -f "$f" ] || fail "the package lacks ${f#"$tmp/root"}"
done
ls "$usr"/lib/libtwinbench_calib.a "$usr"/lib/*/libtwinbench_calib.a >/dev/null 2>&1 ||
  ls "$usr"/lib*/libtwinbench_calib.a >/dev/null 2>&1 || fail "the package lacks libtwinbench_calib.a"
# Architecture rule: the exported estimator's link interface carries nothing of the twin.
targets=("$usr"/lib/cmake/twinbench/twinbenchTargets*.cmake)
grep -q "INTERFACE_LINK_LIBRARIES.*Ceres::ceres" "${targets[@]}" ||
  fail "twinbench::calib's exported link interface lacks Ceres::ceres"
if grep -niE "mujoco|osmesa|[^a-z_]sim[^a-z_]|bench_(io|twin)" "${targets[@]}"; then
  fail "the exported targets name MuJoCo or sim/ (above)"
fi
[ ! -e "$usr/include/twinbench/sim" ] && [ ! -e "$usr/include/twinbench/bench" ] ||
  fail "the package ships sim/ or bench/ headers"

# Everything below runs outside the source and build trees, with no data override.
mkdir -p "$tmp/cwd"
cd "$tmp/cwd"
unset TWINBENCH_DATA_DIR

step "installed twinbench --version"
out=$("$tb" --version) || fail "twinbench --version exit status $?"
[[ "$out" == "twinbench $version ("*")" ]] || fail "--version printed '$out'"
echo "$out"

step "installed twinbench check on installed scenarios"
for s in paper_reinovo.yaml tracker_reinovo.yaml discovery/tracker_clean.yaml; do
  run "$tmp/check.log" "$tb" check "$data/scenarios/$s"
  grep -q . "$tmp/check.log" || fail "check $s printed nothing"
  echo "check $s: $(tail -1 "$tmp/check.log")"
done

step "installed data found from the executable's location (demo reads models/)"
run "$tmp/demo.log" "$tb" demo --samples 3
grep -q "^reinovo_r2:" "$tmp/demo.log" || { cat "$tmp/demo.log"; fail "demo did not run on reinovo_r2"; }

step "missing data: exit 2 naming what is missing; TWINBENCH_DATA_DIR overrides"
mkdir -p "$tmp/bare/bin"
cp "$tb" "$tmp/bare/bin/twinbench"
rc=0; "$tmp/bare/bin/twinbench" demo --samples 1 >"$tmp/bare.log" 2>&1 || rc=$?
[ $rc -eq 2 ] || { cat "$tmp/bare.log"; fail "demo without installed data: exit status $rc, not 2"; }
grep -q "share/twinbench/models" "$tmp/bare.log" && grep -q "TWINBENCH_DATA_DIR" "$tmp/bare.log" ||
  { cat "$tmp/bare.log"; fail "the missing-data error names neither the folder nor TWINBENCH_DATA_DIR"; }
cat "$tmp/bare.log"
rc=0; TWINBENCH_DATA_DIR=$tmp/nowhere "$tb" demo --samples 1 >"$tmp/env.log" 2>&1 || rc=$?
[ $rc -eq 2 ] && grep -q "TWINBENCH_DATA_DIR" "$tmp/env.log" ||
  { cat "$tmp/env.log"; fail "TWINBENCH_DATA_DIR naming no folder: exit status $rc"; }
TWINBENCH_DATA_DIR=$data run "$tmp/env.log" "$tmp/bare/bin/twinbench" demo --samples 1

step "installed bash completion"
completion=$usr/share/bash-completion/completions/twinbench
[ -f "$completion" ] || fail "the package lacks ${completion#"$tmp/root"}"
# complete WORD...: what _twinbench offers for the last word of `twinbench WORD...`.
complete_words() {
  bash -c 'source "$1"; shift; COMP_WORDS=(twinbench "$@"); COMP_CWORD=$#; _twinbench;
           echo "${COMPREPLY[*]}"' _ "$completion" "$@"
}
[ "$(complete_words ch)" = check ] || fail "completion of 'twinbench ch': '$(complete_words ch)'"
[[ " $(complete_words run s.yaml --)" == *" --out "* ]] ||
  fail "completion of 'twinbench run s.yaml --' lacks --out: '$(complete_words run s.yaml --)'"
[[ " $(complete_words --)" == *" --version"* ]] || fail "completion of 'twinbench --' lacks --version"

step "a program built against the exported package (find_package(twinbench CONFIG))"
run "$tmp/consumer-configure.log" cmake -S "$src/tests/packaging/consumer" -B "$tmp/consumer" \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$usr" -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON
grep -q "twinbench_DIR=$usr/lib" "$tmp/consumer-configure.log" ||
  { cat "$tmp/consumer-configure.log"; fail "the consumer did not find the package in $usr"; }
run "$tmp/consumer-build.log" cmake --build "$tmp/consumer" -j2
q=10,-20,30,-40,50,-60
model=$data/models/reinovo_r1.yaml
run "$tmp/consumer-run.log" "$tmp/consumer/calib_consumer" "$model" "$q"
cat "$tmp/consumer-run.log"
mine=$(grep -o 'xyz \[[^]]*\]' "$tmp/consumer-run.log")
theirs=$("$tb" fk "$model" --q "$q" | grep -o 'xyz \[[^]]*\]')
[ -n "$mine" ] && [ "$mine" = "$theirs" ] ||
  fail "consumer's end frame '$mine' differs from installed twinbench fk '$theirs'"
echo "PASS: the .deb installs, runs relocated, and twinbench::calib links"
