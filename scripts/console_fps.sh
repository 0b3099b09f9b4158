#!/usr/bin/env bash
# Frame rate of the console with the predictive ghost over a slow link, as
# docs/performance.md reports it: the stand-in in process, its link delayed
# DELAY s each way, driving at 0.5 m/s, measured over the last 12 of 15 s
# under Xvfb (software GL), RUNS runs each with and without the ghost.
#   scripts/console_fps.sh [BUILD_DIR] [WORLD] [DELAY] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
world=${2:-terrains/flat.world.xml}
delay=${3:-1}
runs=${4:-3}
home=$(mktemp -d)  # fresh settings: the default layout every run
trap 'rm -rf "$home"' EXIT
for i in $(seq "$runs"); do
  for ghost in on off; do
    extra=()
    [ "$ghost" = off ] && extra=(--no-ghost)
    line=$(HOME=$home xvfb-run -a -s "-screen 0 1280x1024x24" "$build/app/simpartner" --world "$world" \
      --delay "$delay" --drive 0.5 --quit-after 15 "${extra[@]}" 2>/dev/null | grep '^frames')
    fps=$(sed -E 's/.*: ([0-9.]+) fps.*/\1/' <<<"$line")
    anchors=$(grep -oE '\(([0-9.]+) per s measured' <<<"$line" | grep -oE '[0-9.]+' || echo -)
    echo "run $i ghost $ghost: $fps fps, re-anchorings/s $anchors"
  done
done
