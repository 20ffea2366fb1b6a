#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz) with Clang, AddressSanitizer and UndefinedBehaviorSanitizer
# in build-fuzz/, and runs each for SECONDS (default 60) from its seed corpus in tests/fuzz/corpus/.
#
#   scripts/fuzz.sh [SECONDS]
#
# The seeds are copied to build-fuzz/corpus/<target>/, which is where new inputs go, so the
# committed corpus changes only by hand. A crash, a sanitizer report, a leak, a timeout (10 s per
# input) or more than 2 GB of memory ends that target with its reproducer in build-fuzz/artifacts/;
# add it under tests/fuzz/corpus/<target>/ and as a regression test. Then the long randomized
# property sweep of the temporal solve (scripts/sweep.sh) runs SWEEP problems (default 10000, with
# ctest's settings: Ipopt capped at 2 CPU s, jerk-limited K at most 30; 0 skips it). Exit 1 if any
# target or the sweep failed.
#
#   scripts/fuzz.sh [SECONDS] [SWEEP]
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH
seconds="${1:-60}"
sweep="${2:-10000}"
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [[ "$seconds" -lt 1 ]]; then
  echo "fuzz: SECONDS must be a positive integer, got '$seconds'" >&2
  exit 2
fi
if ! [[ "$sweep" =~ ^[0-9]+$ ]]; then
  echo "fuzz: SWEEP must be a non-negative integer, got '$sweep'" >&2
  exit 2
fi
./scripts/install_deps.sh fuzz
flags="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -g"
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++-14 \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DTIMEOPT_BUILD_TESTS=OFF -DTIMEOPT_BUILD_BENCHMARKS=OFF -DTIMEOPT_BUILD_EXPERIMENTS=OFF \
  -DTIMEOPT_BUILD_FUZZERS=ON >/dev/null
targets=(problem_json curve_json planner_config waypoints_csv samples_csv cbf octomap)
cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]/#/fuzz_}"
mkdir -p build-fuzz/artifacts
failed=()
for target in "${targets[@]}"; do
  corpus="build-fuzz/corpus/$target"
  mkdir -p "$corpus"
  cp -n tests/fuzz/corpus/"$target"/* "$corpus"/ 2>/dev/null || true
  echo "fuzz: $target for ${seconds} s"
  if ! ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
      "build-fuzz/tests/fuzz/fuzz_$target" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -max_len=65536 -artifact_prefix="build-fuzz/artifacts/${target}-" -print_final_stats=1 \
      >"build-fuzz/$target.log" 2>&1; then
    failed+=("$target")
    echo "fuzz: $target FAILED; see build-fuzz/$target.log and build-fuzz/artifacts/" >&2
  fi
  grep -E "^stat::number_of_executed_units|^#[0-9]+.*DONE" "build-fuzz/$target.log" | tail -1 || true
done
rm -f /tmp/timeopt_fuzz_map_*.bt
if [[ "$sweep" -gt 0 ]]; then
  echo "fuzz: property sweep of $sweep problems"
  ./scripts/sweep.sh "$sweep" 1 --ipopt-seconds 2 --max-jerk-cells 30 || failed+=("property sweep")
fi
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "fuzz: failed: ${failed[*]}" >&2
  exit 1
fi
echo "fuzz: all ${#targets[@]} targets ran ${seconds} s without a failure"
