#!/usr/bin/env bash
# Installs missing Debian packages, builds timeopt in build/ and runs the main job on the shipped
# defaults:
#  1. `timeopt plan` with no arguments: plans on maps/forest_20x20.bt (A* front end, Ceres spatial
#     optimization, certified minimum-time temporal stage) and writes results/plan.csv (100 Hz),
#     results/plan.png (the trajectory over a map slice, coloured by speed) and results/plan.html
#     (the plan in 3D);
#  2. a minimum-jerk curve through examples/waypoints.csv timed by the SOCP, with the speed,
#     velocity and acceleration plot against time (results/waypoints/profile.png).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH  # under env -i bash has a default PATH but does not export it to the tools it runs
# Only what the main job runs: the library and the CLI. Tests, benchmarks and experiments are off,
# so a missing test-only package can never stop it (scripts/test.sh turns them back on).
./scripts/install_deps.sh main
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTIMEOPT_BUILD_TESTS=OFF \
  -DTIMEOPT_BUILD_BENCHMARKS=OFF -DTIMEOPT_BUILD_EXPERIMENTS=OFF
cmake --build build -j"$(nproc)" --target timeopt_cli
mkdir -p results
./build/timeopt plan
./build/timeopt waypoints examples/waypoints.csv --kind minjerk --max-velocity 2 --max-jerk 10 \
  --max-acceleration 2 -K 50 --constraint-mode certified --out-dir results/waypoints
echo "results: $(pwd)/results (plan.csv, plan.png, plan.html, waypoints/)"
