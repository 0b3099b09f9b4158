#!/usr/bin/env bash
# Builds the robot link's libFuzzer target with clang (build-fuzz/) and runs it
# for SECONDS (default 30) from the seed corpus (docs/protocol-fuzzing.md).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
cmake -S . -B build-fuzz -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DSP_WERROR=OFF \
  -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build-fuzz --target fuzz_frame -j"$(nproc 2>/dev/null || echo 2)" >/dev/null
corpus=$(mktemp -d)
cp net/fuzz/corpus/* "$corpus/"
# The corpus copy grows as the fuzzer finds new inputs; the committed one does not.
./build-fuzz/net/fuzz_frame -max_total_time="$seconds" -malloc_limit_mb=1 -max_len=70000 \
  -print_final_stats=1 "$corpus" 2>&1 | grep -E "^(#[0-9]+ +DONE|stat::number_of_executed_units|stat::peak_rss_mb|INFO: Seed)|ERROR|SUMMARY" || true
status=${PIPESTATUS[0]}
rm -rf "$corpus"
exit "$status"
