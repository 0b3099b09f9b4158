#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test (GUI tests under
# xvfb-run, so a display is never needed).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
cd build
xvfb-run -a -s "-screen 0 1280x1024x24" ctest --output-on-failure -j2 "$@"
