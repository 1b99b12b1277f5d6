#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The stability suite under AddressSanitizer + UndefinedBehaviorSanitizer (ctest:
# stability.sanitized): a separate build of stability_tests only (SHARCBAKE_SANITIZE=ON, -O1,
# -g1: line tables are all a report needs; full -g took 45 % more CPU to build), then every
# case of the suite (about 40 s at -O1 with the sanitizers; the sizes are already
# small). Any sanitizer report fails the test (halt_on_error, abort_on_error).
# Usage: sanitized_stability_test.sh SOURCE_DIR WORK_DIR
set -euo pipefail
SRC=$(cd "$1" && pwd)
WORK=$2
JOBS=$(nproc 2>/dev/null || echo 2)
mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd)

# Embree and TBB are not instrumented; their allocations are fine, leaks at exit are not ours.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

echo "== sanitized build of stability_tests in $WORK/build"
cmake -S "$SRC" -B "$WORK/build" -DSHARCBAKE_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-g1 -O1" \
    >"$WORK/configure.log" 2>&1 || { cat "$WORK/configure.log"; exit 1; }
cmake --build "$WORK/build" -j "$JOBS" --target stability_tests >"$WORK/build.log" 2>&1 ||
    { tail -n 60 "$WORK/build.log"; exit 1; }

echo "== stability_tests under ASan + UBSan"
"$WORK/build/bin/stability_tests"
