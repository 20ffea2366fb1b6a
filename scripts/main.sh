#!/usr/bin/env bash
# Installs missing Debian packages, builds timeopt in build/ and runs the main job on the shipped
# default: a minimum-jerk curve through examples/waypoints.csv, timed optimally by the SOCP,
# written as samples and a plot of speed, velocity and acceleration against time.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install_deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2 --target timeopt_cli
./build/timeopt waypoints examples/waypoints.csv --kind minjerk --max-velocity 2 \
  --max-acceleration 2 -K 50 --constraint-mode certified --out-dir results
echo "results: $(pwd)/results"
