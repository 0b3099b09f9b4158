#!/usr/bin/env bash
# Installs what is missing, builds, and starts SimPartner's operator console
# on the default world against the built-in stand-in robot (the twin on
# loopback). Extra arguments go to `simpartner` (see `simpartner --help`).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
if [ -z "${DISPLAY:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ]; then
  # No screen (a server, a container): run on a virtual one, so the console
  # still starts, logs its session and can be screenshotted (`import -window root`).
  echo "run.sh: no DISPLAY; starting the console on a virtual X server (xvfb-run)" >&2
  exec xvfb-run -a -s "-screen 0 1280x800x24" build/app/simpartner "$@"
fi
exec build/app/simpartner "$@"
