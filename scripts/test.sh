#!/usr/bin/env bash
# Installs missing Debian packages, builds timeopt in build/ with its tests, benchmarks and
# experiments, and runs the whole test suite. Skipped tests are listed at the end with the reason
# each one gave (for example the tests that need ../shared beside the repository).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH  # under env -i bash has a default PATH but does not export it to the tools it runs
./scripts/install_deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTIMEOPT_BUILD_TESTS=ON \
  -DTIMEOPT_BUILD_BENCHMARKS=ON -DTIMEOPT_BUILD_EXPERIMENTS=ON
cmake --build build -j"$(nproc)"
status=0
ctest --test-dir build --output-on-failure -j"$(nproc)" --timeout 900 || status=$?
./scripts/list_skipped.sh build/Testing/Temporary/LastTest.log
exit "$status"
