#!/usr/bin/env bash
# The long randomized property sweep of the temporal solve (tests/sweep/property_sweep.cpp):
# COUNT problems (default 10000) from SEED (default 1), in one process per core, in build/
# (Release, tests on). Each process prints its failures, unresolved outcomes and a summary; the
# logs are build/sweep_<part>.log. Exit 1 if any problem failed.
#
#   scripts/sweep.sh [COUNT] [SEED] [OPTIONS...]
#
# OPTIONS go to every process (e.g. --ipopt-seconds 2 --max-jerk-cells 30, ctest's settings).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH
count="${1:-10000}"
seed="${2:-1}"
shift $(($# < 2 ? $# : 2))
for value in "$count" "$seed"; do
  if ! [[ "$value" =~ ^[0-9]+$ ]]; then
    echo "sweep: COUNT and SEED must be non-negative integers, got '$value'" >&2
    exit 2
  fi
done
./scripts/install_deps.sh all
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTIMEOPT_BUILD_TESTS=ON >/dev/null
cmake --build build -j"$(nproc)" --target timeopt_property_sweep
parts="$(nproc)"
per_part=$(((count + parts - 1) / parts))
pids=()
for ((part = 0; part < parts; ++part)); do
  first=$((part * per_part))
  n=$((count - first < per_part ? count - first : per_part))
  [[ $n -gt 0 ]] || break
  build/timeopt_property_sweep --seed "$seed" --first "$first" --count "$n" "$@" >"build/sweep_$part.log" 2>&1 &
  pids+=($!)
done
status=0
for pid in "${pids[@]}"; do wait "$pid" || status=1; done
for ((part = 0; part < ${#pids[@]}; ++part)); do
  grep -E "^property sweep|^largest|^infeasible verdicts" "build/sweep_$part.log" || true
done
if [[ $status -ne 0 ]]; then
  echo "sweep: failures; see build/sweep_*.log (FAIL lines)" >&2
fi
exit $status
