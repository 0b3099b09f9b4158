#!/usr/bin/env bash
# The console installs like a desktop application (issue 34, docs/install.md):
# `cmake --install` into a temporary prefix, then, from an empty working
# directory, the installed programs run on the installed data: simpartner-sim
# check and run on every installed world, simpartner-robot on its default
# world, the console under Xvfb with a screenshot that shows the robot. A
# missing data folder is one clear error naming where it looked. The .deb
# (cpack) holds the desktop entry and the icon, and lintian finds no error.
#
# usage: install_test.sh BUILD_DIR
set -euo pipefail
build=$(cd "$1" && pwd)
tmp=$(mktemp -d)
robot_pid=""
cleanup() {
  [ -n "$robot_pid" ] && kill "$robot_pid" 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
pass() { echo "PASS: $*"; }

prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" > "$tmp/install.log" || { cat "$tmp/install.log"; fail "cmake --install"; }
for f in bin/simpartner bin/simpartner-sim bin/simpartner-robot share/simpartner/robots/workpartner.xml \
         share/simpartner/config/defaults.params share/applications/simpartner.desktop \
         share/icons/hicolor/scalable/apps/simpartner.svg share/icons/hicolor/48x48/apps/simpartner.png \
         share/man/man1/simpartner.1.gz share/man/man1/simpartner-sim.1.gz share/man/man1/simpartner-robot.1.gz \
         share/doc/simpartner/README.md share/doc/simpartner/copyright share/doc/simpartner/changelog.gz; do
  [ -e "$prefix/$f" ] || fail "not installed: $f"
done
desktop-file-validate "$prefix/share/applications/simpartner.desktop" || fail "desktop-file-validate"
zgrep -q "world to run" "$prefix/share/man/man1/simpartner-robot.1.gz" || fail "the robot's man page lacks --world"
pass "installed: programs, data, desktop entry, icons, man pages, docs"

# From an empty working directory, with nothing of the checkout reachable by
# a relative path.
mkdir "$tmp/empty"
cd "$tmp/empty"
worlds=$(cd "$prefix/share/simpartner" && ls terrains/*.world.xml)
[ "$(echo "$worlds" | wc -l)" -ge 5 ] || fail "expected the shipped worlds, found: $worlds"
# shellcheck disable=SC2086
"$prefix/bin/simpartner-sim" check robots/workpartner.xml $worlds > "$tmp/check.log" 2>&1 || { cat "$tmp/check.log"; fail "check"; }
for w in $worlds; do
  "$prefix/bin/simpartner-sim" run --world "$w" --duration 0.5 --rtf max --quiet > "$tmp/run.log" 2>&1 \
    || { cat "$tmp/run.log"; fail "run --world $w"; }
  # The installed copy, not the checkout's.
  grep -q "$prefix/share/simpartner/$w" "$tmp/run.log" || { cat "$tmp/run.log"; fail "run did not load $prefix/share/simpartner/$w"; }
done
pass "simpartner-sim check and run on $(echo "$worlds" | wc -l) installed worlds"

# The robot with its default world: it listens, and stops on SIGTERM.
"$prefix/bin/simpartner-robot" --no-log --port 0 > "$tmp/robot.out" 2> "$tmp/robot.err" &
robot_pid=$!
for _ in $(seq 100); do
  grep -q "listening" "$tmp/robot.out" "$tmp/robot.err" && break
  kill -0 "$robot_pid" 2>/dev/null || break
  sleep 0.1
done
grep -q "listening" "$tmp/robot.out" "$tmp/robot.err" || { cat "$tmp/robot.out" "$tmp/robot.err"; fail "the robot did not start"; }
grep -q "$prefix/share/simpartner/terrains/flat.world.xml" "$tmp/robot.out" "$tmp/robot.err" \
  || { cat "$tmp/robot.out" "$tmp/robot.err"; fail "the robot did not say it runs the installed default world"; }
kill -TERM "$robot_pid"
wait "$robot_pid" || fail "the robot's exit status on SIGTERM: $?"
robot_pid=""
pass "simpartner-robot on the installed default world"

# The console under Xvfb: a screenshot that shows the robot (its amber
# bodies: saturated orange, which neither the ground nor the sky is), in the
# 3D view's part of the 1280x800 window (the plots below have an orange line).
export HOME=$tmp/home XDG_RUNTIME_DIR=$tmp/run
mkdir -p "$HOME" "$XDG_RUNTIME_DIR"
chmod 700 "$XDG_RUNTIME_DIR"
xvfb-run -a -s "-screen 0 1280x800x24" "$prefix/bin/simpartner" --no-log --quit-after 5 --screenshot "$tmp/shot.png" \
  > "$tmp/console.log" 2>&1 || { cat "$tmp/console.log"; fail "the console"; }
[ -s "$tmp/shot.png" ] || fail "no screenshot"
amber=$(convert "$tmp/shot.png" -crop 880x560+0+30 +repage ppm:- | python3 -c '
import sys
d = sys.stdin.buffer.read().split(b"\n", 3)
px = d[3]
print(sum(1 for i in range(0, len(px), 3) if px[i] > 100 and px[i] > 1.3 * px[i + 1] and px[i + 1] > 2.5 * px[i + 2]))')
# The flat world's robot in the default view covers about 6000 such pixels.
[ "$amber" -gt 1500 ] || fail "the screenshot shows no robot ($amber amber pixels)"
pass "the installed console shows the robot ($amber amber pixels)"

# Bad input: the data folder missing, or $SIMPARTNER_DATA naming none.
mv "$prefix/share/simpartner" "$prefix/share/simpartner.away"
if "$prefix/bin/simpartner-robot" --no-log --port 0 > /dev/null 2> "$tmp/err"; then fail "the robot ran without its data"; fi
grep -q "terrains/flat.world.xml: error: not found; looked in the working directory ($tmp/empty), $prefix/share/simpartner (installed, missing)" "$tmp/err" \
  || { cat "$tmp/err"; fail "the robot's error does not say where it looked"; }
status=0
# Offscreen: the console stops before it shows a window, and xvfb-run's own
# clean-up once failed on CI here (exit 5), which is not what is tested.
QT_QPA_PLATFORM=offscreen timeout 60 "$prefix/bin/simpartner" --no-log > /dev/null 2> "$tmp/err" || status=$?
[ "$status" = 1 ] || { cat "$tmp/err"; fail "the console without its data: exit $status, expected 1"; }
grep -q "looked in the working directory" "$tmp/err" || { cat "$tmp/err"; fail "the console's error does not say where it looked"; }
mv "$prefix/share/simpartner.away" "$prefix/share/simpartner"
if SIMPARTNER_DATA=/nonexistent/sp "$prefix/bin/simpartner-sim" validate --quick --out "$tmp/v" > /dev/null 2> "$tmp/err"; then
  fail "validate ran with SIMPARTNER_DATA naming no folder"
fi
grep -q '\$SIMPARTNER_DATA: error: /nonexistent/sp: no such folder' "$tmp/err" || { cat "$tmp/err"; fail "validate's error"; }
pass "a missing data folder: one error naming where it looked (robot, console, validate)"

# The .deb: the same tree under /usr, the desktop entry and icon in it.
cpack --config "$build/CPackConfig.cmake" -B "$tmp/pkg" > "$tmp/cpack.log" 2>&1 || { cat "$tmp/cpack.log"; fail "cpack"; }
deb=$(ls "$tmp"/pkg/simpartner_*.deb)
dpkg-deb --contents "$deb" > "$tmp/contents"
for f in ./usr/share/applications/simpartner.desktop ./usr/share/icons/hicolor/256x256/apps/simpartner.png \
         ./usr/share/icons/hicolor/scalable/apps/simpartner.svg ./usr/bin/simpartner ./usr/share/simpartner/robots/workpartner.xml; do
  grep -q " $f\$" "$tmp/contents" || fail "the .deb lacks $f"
done
dpkg-deb --field "$deb" Depends | grep -q "libode8" || fail "the .deb does not depend on ODE's package"
# The ROS component stays out of it: the console's package needs no ROS.
if grep -q "simpartner-ros-" "$tmp/contents" || dpkg-deb --field "$deb" Depends | grep -q "libros"; then
  fail "the .deb holds the ROS component or depends on ROS"
fi
lintian --fail-on error "$deb" > "$tmp/lintian.log" 2>&1 || { cat "$tmp/lintian.log"; fail "lintian reports errors"; }
pass "the .deb: desktop entry, icon, programs, data; depends on $(dpkg-deb --field "$deb" Depends | tr ',' '\n' | wc -l) packages; lintian: no error"
