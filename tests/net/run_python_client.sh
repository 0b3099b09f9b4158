#!/bin/sh
# Runs docs/examples/simpartner_client.py against the stand-in robot:
# starts ROBOT (simpartner-robot) on a free port of 127.0.0.1, waits for its
# `listening on` line, runs the example, stops the robot, and exits with the
# example's code.
#
#   run_python_client.sh ROBOT SOURCE_DIR [PYTHON]
set -u
robot=$1
src=$2
python=${3:-python3}
token=00112233445566778899aabbccddeeff

out=$(mktemp)
trap 'rm -f "$out"' EXIT
# --port 0: the robot picks a free port and prints it; --no-log: no
# sessions/ folder left behind.
"$robot" --world "$src/terrains/flat.world.xml" --port 0 --token "$token" --no-log >"$out" 2>&1 &
pid=$!

port=
for _ in $(seq 300); do
  port=$(sed -n 's/^listening on 127\.0\.0\.1:\([0-9][0-9]*\).*/\1/p' "$out")
  [ -n "$port" ] && break
  kill -0 "$pid" 2>/dev/null || break
  sleep 0.1
done
if [ -z "$port" ]; then
  echo "error: the robot did not report a port within 30 s:" >&2
  cat "$out" >&2
  kill "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  exit 1
fi

"$python" "$src/docs/examples/simpartner_client.py" --host 127.0.0.1 --port "$port" --token "$token" --seconds 3
code=$?

kill "$pid" 2>/dev/null
wait "$pid" 2>/dev/null
exit $code
