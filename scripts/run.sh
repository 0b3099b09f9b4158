#!/usr/bin/env bash
# Installs what is missing, builds, and runs SimPartner's main job: the twin
# headless on the default world, driving a short demo sequence in real time.
# Extra arguments go to `simpartner-sim run`.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
exec build/app/simpartner-sim run --world terrains/flat.world.xml \
  --commands terrains/demo.seq --duration 12 "$@"
