#!/usr/bin/env bash
# Crash safety of the session log (issue 6, docs/session-format.md).
#
#   scripts/crash_test.sh [N]        (default 100; run from the source root)
#
# N times: starts `simpartner-sim run ... --rtf 1 --log FILE`, kills it with
# SIGKILL after a random 0.3-3 s, then runs simpartner-logcheck on FILE: it
# must open as a session log, pass `PRAGMA integrity_check`, and its last
# sample must be at most 100 ms behind the sim time the run can have reached
# at the kill. That bound is (kill time - FILE's birth time) x rtf, both on
# CLOCK_REALTIME: the kill time is $EPOCHREALTIME read right after kill(2)
# returns, the birth time is the kernel's btime of FILE (see app/tools/log_check.cpp
# for why this over-estimates the loss, never under-estimates it).
#
# Environment: SP_BUILD_DIR (default build) holds app/simpartner-sim and
# app/simpartner-logcheck; SP_CRASH_MAX_LOSS_MS (default 100) is the limit.
# The loss printed is an upper bound that also counts the run's start-up and
# any lag of its pacer behind the wall clock, both of which grow when the
# machine is loaded (up to 201 ms seen under load, against 25 ms batches);
# ctest runs it with the bound stated for a loaded machine, 300 ms.
# Prints one line per run and a summary; exits 1 if any run failed.
set -u
N=${1:-100}
LIMIT=${SP_CRASH_MAX_LOSS_MS:-100}
BUILD=${SP_BUILD_DIR:-build}
SIM=$BUILD/app/simpartner-sim
CHECK=$BUILD/app/simpartner-logcheck
for exe in "$SIM" "$CHECK"; do
  [[ -x $exe ]] || { echo "crash_test: $exe not built" >&2; exit 2; }
done
DIR=$(mktemp -d "${TMPDIR:-/tmp}/sp_crash.XXXXXX")
trap 'rm -rf "$DIR"' EXIT

failures=0
worst=-1e9
nolog=0
for ((i = 1; i <= N; ++i)); do
  log=$DIR/run$i.splog
  delay_ms=$((300 + RANDOM % 2701))
  "$SIM" run --world terrains/flat.world.xml --commands terrains/demo.seq --rtf 1 --duration 30 --quiet \
    --log "$log" >"$DIR/out$i.txt" 2>&1 &
  pid=$!
  sleep "$(printf '%d.%03d' $((delay_ms / 1000)) $((delay_ms % 1000)))"
  kill -KILL "$pid"
  killed_at=$EPOCHREALTIME
  wait "$pid" 2>/dev/null
  if [[ ! -e $log ]]; then
    # Killed before the log was created: nothing was logged, nothing lost.
    echo "run $i: delay ${delay_ms} ms: no log yet"
    nolog=$((nolog + 1))
    continue
  fi
  result=$("$CHECK" "$log" --killed-at "$killed_at" --rtf 1 --max-loss-ms "$LIMIT")
  status=$?
  echo "run $i: delay ${delay_ms} ms: $result"
  if ((status == 3)); then
    nolog=$((nolog + 1))
    rm -f "$log" "$log-wal" "$log-shm"
    continue
  fi
  if ((status != 0)); then
    failures=$((failures + 1))
  fi
  loss=$(sed -n 's/.*loss_ms=\([-0-9.]*\).*/\1/p' <<<"$result")
  if [[ -n $loss ]]; then
    worst=$(awk -v a="$worst" -v b="$loss" 'BEGIN { print (b > a) ? b : a }')
  fi
  rm -f "$log" "$log-wal" "$log-shm"
done
echo "crash_test: $N runs, $failures failures, $nolog killed before the log existed, worst loss ${worst} ms (limit ${LIMIT} ms)"
((failures == 0))
