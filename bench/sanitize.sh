#!/usr/bin/env bash
# The C++ core under AddressSanitizer + UndefinedBehaviorSanitizer (+ LeakSanitizer), with Eigen's
# and libstdc++'s assertions on: builds only the bench in build-sanitize/ (-DADPARM_SANITIZE=ON, see
# CMakeLists.txt) and runs it briefly with --checks: the paper loop, fixed extrapolation points, the
# 16-run batch on 1 and 2 threads, the URDF arms in the closed loop (50 steps of the planar 3-link
# arm and the UR5, quadratic and structured bases, N = 0 and 10), then local/grid points,
# tracking, the other controllers, a diverging run, chunked and threaded runs, a streamed batch
# (window 2) stopped part-way and resumed, invalid settings that must throw, and the dense kernels
# of each set the CPU runs on random shapes (bench/dense_kernel_checks.hpp); then the expression basis bench (adparm_bench_basis
# --checks: exactness, no heap allocation per evaluation, invalid programs and sizes) and the
# structured basis bench (adparm_bench_structured_basis, 2000 evaluations per arm: the HJB error at
# W* at round-off, copies evaluate alike, no heap allocation).
# Any finding stops the bench and makes this script exit non-zero.
#
# Usage: bench/sanitize.sh [simulated_seconds [points ...]]   (default: 1 s, N = 0 and 10)
# Needs what the plain CMake build needs (README): cmake, ninja, pip install cmeel-eigen.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$root/build-sanitize"
start=$SECONDS

generator=()
if [ ! -f "$build/CMakeCache.txt" ] && command -v ninja >/dev/null; then
  generator=(-G Ninja)
fi
cmake -S "$root" -B "$build" ${generator[@]+"${generator[@]}"} -DADPARM_SANITIZE=ON -DADPARM_BUILD_BENCH=ON
cmake --build "$build" --target adparm_bench adparm_bench_basis adparm_bench_structured_basis
built=$SECONDS

# LeakSanitizer works in this container (it needs to stop the threads with ptrace; where it cannot,
# e.g. under a debugger or without the capability, set detect_leaks=0 here).
export ASAN_OPTIONS="detect_leaks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1:strict_string_checks=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
if [ $# -eq 0 ]; then
  set -- 1 0 10
fi
status=0
"$build/adparm_bench" --checks "$@" || status=$?
# The expression basis: bit for bit against the hand-written bases, no allocation (ASan's hook
# counts), then invalid programs and sizes.
"$build/adparm_bench_basis" --checks 20000 || status=$?
# The structured basis of URDF arms: HJB error at W*, copies, no allocation (ASan's hook counts).
"$build/adparm_bench_structured_basis" 2000 || status=$?

echo "sanitize: build $((built - start)) s, run $((SECONDS - built)) s, exit status $status" >&2
exit "$status"
