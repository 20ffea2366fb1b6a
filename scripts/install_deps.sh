#!/usr/bin/env bash
# Installs the Debian 12 packages timeopt needs that are not installed yet.
#
#   scripts/install_deps.sh          everything: the library, the CLI, tests, benchmarks, experiments
#   scripts/install_deps.sh main     only what the library and the `timeopt` CLI need (the main job)
#   scripts/install_deps.sh fuzz     the library's needs plus Clang and its libFuzzer runtime (scripts/fuzz.sh)
#
# Idempotent: when everything is present it only runs dpkg-query and exits. Each package is listed
# with what uses it, so that a new find_package/pkg_check_modules or script tool gets its line here
# (scripts/check_fresh_machine.sh catches a forgotten one on a bare Debian 12).
set -euo pipefail

group="${1:-all}"
case "$group" in
  main | all | fuzz) ;;
  *) echo "install_deps: unknown group '$group' (expected 'main', 'all' or 'fuzz')" >&2; exit 2 ;;
esac

# The library and the CLI (CMakeLists.txt, top part).
MAIN_PACKAGES=(
  build-essential cmake pkg-config  # compiler, CMake, pkg_check_modules
  libeigen3-dev                     # find_package(Eigen3)
  libceres-dev                      # find_package(Ceres): the spatial stage
  liboctomap-dev                    # find_package(octomap): maps
  coinor-libipopt-dev               # pkg_check_modules(ipopt): the NLP backend
  nlohmann-json3-dev                # find_package(nlohmann_json): the JSON contract
  libcli11-dev                      # find_package(CLI11): the command line
  libcairo2-dev                     # pkg_check_modules(cairo): PNG plots
  fonts-dejavu-core                 # a font for the plots' text (a minimal root may have none)
  python3-rosbag python3-nav-msgs   # `timeopt export --format rosbag` (python/timeopt_rosbag.py)
  python3-trajectory-msgs python3-visualization-msgs
  libjs-three libjs-chart.js        # the 3D page (plan --html, view), inlined when it is written
)
# Tests, benchmarks and experiments (TIMEOPT_BUILD_TESTS / _BENCHMARKS / _EXPERIMENTS).
TEST_PACKAGES=(
  libgtest-dev libgmock-dev         # find_package(GTest): GTest::gtest_main and GTest::gmock
  libbenchmark-dev                  # find_package(benchmark): benchmarks/
  libdynamicedt3d-dev               # find_package(dynamicEDT3D): the ESDF comparison test
  python3-cvxopt python3-numpy      # tests/temporal/cvxopt_cross_check.py (second solver)
  pybind11-dev python3-dev          # the Python module (TIMEOPT_BUILD_PYTHON)
  python3-pytest python3-scipy      # tests/python (pytest; scipy.sparse for the conic solver)
  python3-jsonschema                # tests/io/validate_schemas.py (docs/schema against real outputs)
  python3-distributed python3-dask  # tests/python/test_batch.py (solve_many on a Dask LocalCluster)
  chromium                          # tests/viz/check_plan_page.py (the 3D page in headless Chromium)
)

# Fuzzing (scripts/fuzz.sh, TIMEOPT_BUILD_FUZZERS).
FUZZ_PACKAGES=(
  clang-14                          # the compiler libFuzzer comes with
  libclang-rt-14-dev                # libclang_rt.fuzzer and the sanitizer runtimes
)

PACKAGES=("${MAIN_PACKAGES[@]}")
if [[ "$group" == all ]]; then PACKAGES+=("${TEST_PACKAGES[@]}"); fi
if [[ "$group" == fuzz ]]; then PACKAGES+=("${FUZZ_PACKAGES[@]}"); fi

missing=()
for pkg in "${PACKAGES[@]}"; do
  status="$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)"
  if [[ "$status" != "install ok installed" ]]; then
    missing+=("$pkg")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "install_deps: all ${#PACKAGES[@]} packages of group '$group' present"
  exit 0
fi

SUDO=""
if [[ "$(id -u)" -ne 0 ]]; then
  if command -v sudo >/dev/null 2>&1; then
    SUDO="sudo"
  else
    echo "install_deps: need root or sudo to install: ${missing[*]}" >&2
    exit 1
  fi
fi

echo "install_deps: installing ${missing[*]}"
# Under an empty environment (env -i) bash's default PATH is not exported and has no sbin folders,
# where dpkg finds ldconfig and start-stop-daemon.
case ":${PATH:-}:" in
  *:/usr/sbin:*) export PATH ;;
  *) export PATH="/usr/local/sbin:/usr/sbin:/sbin:${PATH:-/usr/local/bin:/usr/bin:/bin}" ;;
esac
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
