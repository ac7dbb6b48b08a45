#!/bin/bash
# The installed program (docs/user/install.md): `cmake --install BUILD --prefix P` into a temporary
# prefix, then, from an empty directory and with the source tree's scenes out of reach,
#   P/bin/sphxr finds its scenes by name in P/share/sphxr/scenes and runs headless;
#   P/bin/sphxr --xr runs a session on the simulated headset through P/lib/sphxr's manifest;
#   Debian's python3 imports the installed sphxr module, runs a scene of the prefix and a one-case sweep;
#   `cpack -G DEB` makes a .deb that holds the same files under /usr and whose dependencies are all
#   installed on this machine (scripts/setup.sh's packages and the libraries they bring).
# Usage: install_test.sh BUILD_DIR WORK_DIR XR PYTHON   (tests/CMakeLists.txt, ctest test `install`)
#   XR: 1 when the build has the simulated headset; PYTHON: the module's interpreter, empty without it.
set -u
build=$1 work=$2 xr=$3 python=$4
fail() { echo "install_test: FAIL: $*" >&2; exit 1; }
step() { echo "install_test: $*"; }
rm -rf "$work" && mkdir -p "$work/run" || fail "cannot make $work"
prefix=$work/prefix
cmake --install "$build" --prefix "$prefix" > "$work/install.log" 2>&1 || { cat "$work/install.log"; fail "cmake --install"; }

files="bin/sphxr share/sphxr/scenes/stir.json share/sphxr/scenes/dam_break.json share/sphxr/scenes/stir_paddle.csv
       share/sphxr/data/martin_moyce_1952.csv share/doc/sphxr/README.md share/doc/sphxr/user/install.md
       share/doc/sphxr/user/python.md"
[ "$xr" = 1 ] && files+=" lib/sphxr/sphxr_sim_runtime.json lib/sphxr/libsphxr_sim_runtime.so"
[ -n "$python" ] && files+=" lib/python3/dist-packages/sphxr/__init__.py lib/python3/dist-packages/sphxr/sweep.py
                            share/doc/sphxr/examples/python/dam_break.py"
for f in $files; do
  [ -e "$prefix/$f" ] || fail "the install has no $f"
done
[ "$xr" != 1 ] || grep -q '"library_path": "./libsphxr_sim_runtime.so"' "$prefix/lib/sphxr/sphxr_sim_runtime.json" ||
  fail "the installed manifest does not name the library beside it: $(cat "$prefix/lib/sphxr/sphxr_sim_runtime.json")"

# A scene that only the prefix has: found by name, it can only have come from P/share/sphxr/scenes.
cat > "$prefix/share/sphxr/scenes/install_test_tank.json" <<'JSON'
{
  "name": "install_test_tank",
  "solver": { "spacing": 0.01, "stiffness": 57000.0, "viscosity": 0.3, "boundary_viscosity": 0.3, "max_dt": 0.001 },
  "tank": { "min": [0.0, 0.0, 0.0], "max": [0.2, 0.2, 0.2] },
  "fluid": [ { "min": [0.0, 0.0, 0.0], "max": [0.2, 0.05, 0.2] } ]
}
JSON
cd "$work/run" || fail "cd"
export OMP_WAIT_POLICY=passive
unset XR_RUNTIME_JSON

step "sphxr --headless --scene stir (a shipped scene by name)"
out=$("$prefix/bin/sphxr" --headless --scene stir --steps 2 --threads 1 2>&1) || fail "sphxr --scene stir: $out"
grep -q "sphxr summary: stir" <<<"$out" || fail "no summary of stir: $out"
step "sphxr --headless --scene install_test_tank (a scene only the prefix has)"
out=$("$prefix/bin/sphxr" --headless --scene install_test_tank --steps 2 --threads 1 2>&1) || fail "$out"
grep -q "sphxr summary: install_test_tank" <<<"$out" || fail "no summary: $out"
out=$("$prefix/bin/sphxr" --headless --scene no_such_scene --steps 1 2>&1) && fail "a missing scene ran: $out"
grep -q "$prefix/share/sphxr/scenes" <<<"$out" || fail "the message does not name the installed scenes: $out"

if [ "$xr" = 1 ]; then
step "sphxr --xr on the installed simulated headset"
# A private X server (the display number chosen by Xvfb itself, as tests/xvfb.h does).
Xvfb -displayfd 3 -screen 0 640x480x24 -nolisten tcp 3>"$work/display" 2>/dev/null &
xvfb=$!
trap 'kill $xvfb 2>/dev/null' EXIT
for _ in $(seq 200); do grep -q . "$work/display" 2>/dev/null && break; sleep 0.1; done
display=$(head -1 "$work/display")
[ -n "$display" ] || fail "Xvfb did not start"
out=$(DISPLAY=:$display XR_RUNTIME_JSON=$prefix/lib/sphxr/sphxr_sim_runtime.json SPHXR_SIM_XR_EYE_SIZE=64x48 \
      "$prefix/bin/sphxr" --xr --scene install_test_tank --frame-limit 5 --quality scene --threads 1 \
      --window-size 160x120 2>&1) || fail "sphxr --xr: $out"
grep -q "sphxr --xr: OpenXR session ended after 5 frames" <<<"$out" || fail "no headset session: $out"
grep -q "sphxr simulated headset" <<<"$out" || fail "not the simulated headset: $out"
kill $xvfb 2>/dev/null
fi

if [ -n "$python" ]; then
step "import sphxr from the install ($python)"
site=$prefix/lib/python3/dist-packages
PYTHONPATH=$site PREFIX=$prefix "$python" - <<'PY' || fail "the installed module"
import os
import sphxr
prefix = os.environ["PREFIX"]
assert sphxr.__file__.startswith(prefix), sphxr.__file__
assert sphxr.find_scene("install_test_tank") == os.path.join(prefix, "share/sphxr/scenes/install_test_tank.json")
assert sphxr.data_dir() == os.path.join(prefix, "share/sphxr/data"), sphxr.data_dir()
# A name not found is one line naming the installed scenes, its control characters escaped.
try:
    sphxr.find_scene("no_such\x1b]0;owned\x07\u202e")
    raise AssertionError("found")
except sphxr.Error as e:
    message = str(e)
assert "no_such\\x1B]0;owned\\x07\\u202E: no scene of that name" in message, message
assert os.path.join(prefix, "share/sphxr/scenes") in message, message
assert all(ord(c) >= 0x20 for c in message) and "\u202e" not in message, repr(message)
sphxr.set_log_level("warn")
run = sphxr.Run("install_test_tank", threads=1).step(2)
assert run.positions().shape == (run.fluid_count, 3) and run.steps == 2
PY
PYTHONPATH=$site "$python" -m sphxr.sweep install_test_tank --steps 2 --grid spacing=0.02 --workers 1 --quiet \
  --out "$work/run/sweep.csv" || fail "a sweep from the install"
grep -q "^0,0.02,ok,1," "$work/run/sweep.csv" || fail "the sweep's table: $(cat "$work/run/sweep.csv")"
fi

step "cpack -G DEB"
if ! command -v dpkg-deb > /dev/null || ! command -v dpkg-shlibdeps > /dev/null; then
  step "no dpkg-deb or dpkg-shlibdeps (dpkg-dev): the .deb is not checked"
  exit 0
fi
(cd "$work" && cpack -G DEB -B "$work/deb" --config "$build/CPackConfig.cmake") > "$work/cpack.log" 2>&1 ||
  { cat "$work/cpack.log"; fail "cpack -G DEB"; }
deb=$(ls "$work"/deb/*.deb 2>/dev/null | head -1)
[ -n "$deb" ] || fail "cpack made no .deb: $(cat "$work/cpack.log")"
contents=$(dpkg-deb -c "$deb")
for f in $files; do
  f=./usr/$f
  grep -q " $f\$" <<<"$contents" || fail "the .deb has no $f"
done
depends=$(dpkg-deb -f "$deb" Depends)
step "Depends: $depends"
wants="libopenxr-loader1 libgomp1 libglfw3"
[ -n "$python" ] && wants+=" python3-numpy python3-distributed python3-dask"
for want in $wants; do
  grep -qw -- "$want" <<<"$depends" || fail "the .deb does not depend on $want: $depends"
done
# Every dependency is a package this machine has (scripts/setup.sh installed it or it came with one).
IFS=',' read -ra items <<<"$depends"
for item in "${items[@]}"; do
  name=$(sed -e 's/^ *//' -e 's/[ (].*//' <<<"$item")
  dpkg-query -W -f='${Status}' "$name" 2>/dev/null | grep -q "install ok installed" ||
    fail "the .deb depends on $name, which is not installed here (not one of setup.sh's packages)"
done
step "ok"
