#!/usr/bin/env bash
# The speed/accuracy table behind the default physics (docs/performance.md):
# the full validation suite at each physics setting, one after the other on
# an otherwise idle machine. Prints a Markdown row per setting: experiments
# passed, the judged metrics that failed, and the suite's wall time.
#
#   scripts/physics_table.sh [BUILD_DIR] [STEP_S/ITERATIONS ...]
#   e.g. scripts/physics_table.sh build 0.001/50 0.001/40 0.002/50
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
settings=("$@")
[ ${#settings[@]} -gt 0 ] || settings=(0.001/50 0.001/40 0.001/30 0.001/20 0.002/50)
sim="$build/app/simpartner-sim"
[ -x "$sim" ] || { echo "physics_table.sh: $sim not built" >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| step | iterations | experiments passed | judged metrics failed | suite wall time [s] |"
echo "|---|---|---|---|---|"
for s in "${settings[@]}"; do
  step=${s%/*} iterations=${s#*/}
  dir="$out/$step-$iterations"
  start=$(date +%s.%N)
  "$sim" validate --out "$dir" --set "physics.step=$step" --set "physics.iterations=$iterations" > "$dir.log" 2>&1 || true
  end=$(date +%s.%N)
  passed=$(grep -o '[0-9]* of [0-9]* experiments pass' "$dir.log" || echo "did not finish")
  failed=$(grep -F '| **fail** |' "$dir/report.md" 2>/dev/null | awk -F'|' '{gsub(/^ +| +$/, "", $3); gsub(/^ +| +$/, "", $4); printf "%s%s: %s", sep, $3, $4; sep="; "}')
  printf "| %s ms | %s | %s | %s | %.0f |\n" "$(awk -v s="$step" 'BEGIN{print s*1000}')" "$iterations" "$passed" \
    "${failed:-none}" "$(awk -v a="$start" -v b="$end" 'BEGIN{print b-a}')"
done
