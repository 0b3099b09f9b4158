#!/usr/bin/env bash
# The end state hashes of seven fixed headless runs (issue 11's list): a
# refactoring that must not change the physics prints the same seven lines
# before and after. Pass another build's folder to compare two builds:
#   scripts/state_hashes.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
sim=${1:-build}/app/simpartner-sim
run() {  # NAME, then simpartner-sim run arguments
  local name=$1
  shift
  local hash
  # A run that diverges ends with its report (and a non-zero exit): its hash is printed too.
  hash=$("$sim" run "$@" --rtf max 2>&1 | grep -oE 'state hash [0-9a-f]{16}' | tail -1 | cut -d' ' -f3 || true)
  echo "$name ${hash:-none}"
}
run "flat 10 s" --world terrains/flat.world.xml --commands terrains/demo.seq --duration 10
run "test track 10 s" --world terrains/test_track.world.xml --commands terrains/demo.seq --duration 10
run "test track 5 s, no commands" --world terrains/test_track.world.xml --duration 5
run "bumpy 6 s" --world terrains/bumpy.world.xml --commands terrains/demo.seq --duration 6
run "pick and place 30 s" --world terrains/pick_place.world.xml --commands terrains/pick_place.seq --duration 30
run "laser wall 5 s" --world terrains/laser_wall.world.xml --commands terrains/demo.seq --duration 5
run "ice 5 s, exact solver" --world terrains/ice.world.xml --commands terrains/demo.seq --duration 5 --set physics.solver=exact
