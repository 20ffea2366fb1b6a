#!/usr/bin/env bash
# Builds the library, the CLI and the test suite with AddressSanitizer and UndefinedBehaviorSanitizer
# (GCC; every report is fatal, float-cast-overflow included) in build-sanitize/, and runs the whole
# ctest suite there. Third-party leaks are suppressed by tests/sanitize/lsan.supp (each entry says
# why); nothing of ours is. Benchmarks and experiments are not built: they exercise the same code.
#
#   scripts/sanitize.sh
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH
./scripts/install_deps.sh
# EIGEN_MALLOC_ALREADY_ALIGNED=1: Eigen switches to its own aligned allocator when it sees
# __SANITIZE_ADDRESS__, but Debian's libceres was built with malloc's alignment; a matrix that Ceres
# allocates and our code frees (ceres::GradientChecker's probe results) then fails in
# handmade_aligned_free. glibc's and ASan's malloc both align to 16 bytes on x86-64.
flags="-fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all -fno-omit-frame-pointer -g1"
flags+=" -DEIGEN_MALLOC_ALREADY_ALIGNED=1"
# The Python module is off here: an instrumented module would need libasan preloaded into the
# interpreter. The normal suite tests it.
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DTIMEOPT_BUILD_TESTS=ON -DTIMEOPT_BUILD_BENCHMARKS=OFF -DTIMEOPT_BUILD_EXPERIMENTS=OFF \
  -DTIMEOPT_BUILD_PYTHON=OFF >/dev/null
cmake --build build-sanitize -j"$(nproc)"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1:strict_string_checks=1:detect_stack_use_after_return=0"
export LSAN_OPTIONS="suppressions=$PWD/tests/sanitize/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
status=0
# consumer.find_package_and_link builds a separate project against the installed static libraries,
# without these flags, so it cannot link their sanitizer calls; the normal suite runs it.
ctest --test-dir build-sanitize --output-on-failure -j"$(nproc)" --timeout 1800 \
  -E '^consumer\.find_package_and_link$' || status=$?
./scripts/list_skipped.sh build-sanitize/Testing/Temporary/LastTest.log
exit "$status"
