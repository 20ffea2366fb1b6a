#!/usr/bin/env bash
# Installs missing Debian packages, builds timeopt in build/ and runs the main job on the shipped
# default input, printing where the results went.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install_deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2 --target timeopt_cli
mkdir -p results
./build/timeopt curve examples/waypoints.csv --kind minjerk -o results/curve.json
echo "results: $(pwd)/results/curve.json"
