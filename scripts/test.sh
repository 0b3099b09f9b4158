#!/usr/bin/env bash
# Installs what is missing, builds, fuzzes the robot link's codec for 30 s
# (scripts/fuzz.sh), and runs every test (GUI tests under xvfb-run, so a
# display is never needed). ctest's summary is the last thing printed.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
echo "fuzzing the link codec for 30 s"
scripts/fuzz.sh 30
cd build
xvfb-run -a -s "-screen 0 1280x1024x24" ctest --output-on-failure -j2 "$@"
