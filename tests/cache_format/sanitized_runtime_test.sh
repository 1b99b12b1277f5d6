#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The runtime library under ASan + UBSan, then fuzzed (ctest: cache_format.sanitized_and_fuzzed).
#   (a) a separate runtime-only build (SHARCBAKE_BUILD_TOOLS=OFF, SHARCBAKE_SANITIZE=ON, Debug)
#       of the cache_format tests, run with ctest (round trip, golden, reject tests, lookups...);
#   (b) with clang++: tests/cache_format/fuzz_cache_file.cpp + cache_format/src/*.cpp under
#       -fsanitize=fuzzer,address,undefined, run for FUZZ_SECONDS (default 60) on a copy of the
#       golden seed corpus, then fuzz_checkpoint_file.cpp for CHECKPOINT_FUZZ_SECONDS (default
#       30) on the golden checkpoint; any crash, leak, sanitizer report or timeout fails the test.
# Without clang++ (b) is skipped: exit 77 (ctest SKIP_RETURN_CODE).
# Usage: sanitized_runtime_test.sh SOURCE_DIR WORK_DIR
set -euo pipefail
SRC=$(cd "$1" && pwd)
WORK=$2
FUZZ_SECONDS=${FUZZ_SECONDS:-60}
CHECKPOINT_FUZZ_SECONDS=${CHECKPOINT_FUZZ_SECONDS:-30}
JOBS=$(nproc 2>/dev/null || echo 2)
mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd)

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

echo "== (a) sanitized runtime build + cache_format tests in $WORK/build"
cmake -S "$SRC" -B "$WORK/build" -DSHARCBAKE_BUILD_TOOLS=OFF -DSHARCBAKE_SANITIZE=ON \
    -DCMAKE_BUILD_TYPE=Debug >"$WORK/configure.log" 2>&1 || { cat "$WORK/configure.log"; exit 1; }
cmake --build "$WORK/build" -j "$JOBS" --target cache_file_tests hash_grid_tests hash_grid_vector_dump \
    sdk_target_tests
# install_consumer needs a full build to install; the generator check is not runtime code.
(cd "$WORK/build" && ctest --output-on-failure -j "$JOBS" \
    -E 'install_consumer|scenes\.generator_check|sanitized_and_fuzzed')

echo "== (b) libFuzzer harness"
CXX_FUZZ=${CLANGXX:-$(command -v clang++ || true)}
if [ -z "$CXX_FUZZ" ]; then
    echo "SKIP: clang++ not found; the sanitized tests passed, the fuzzer did not run (apt-get install clang libclang-rt-14-dev)"
    exit 77
fi
rm -rf "$WORK/fuzz" && mkdir -p "$WORK/fuzz"
. "$SRC/tests/fuzz_support.sh"
# fuzz NAME SEED_GLOB SECONDS: build tests/cache_format/fuzz_NAME.cpp, run its seeds, then fuzz.
fuzz() {
    local name=$1 seeds=$2 seconds=$3 dir="$WORK/fuzz/$1"
    mkdir -p "$dir/corpus"
    "$CXX_FUZZ" -std=c++17 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
        -ffp-contract=off -I"$SRC/cache_format/include" \
        "$SRC/tests/cache_format/fuzz_$name.cpp" "$SRC"/cache_format/src/*.cpp -o "$dir/fuzz_$name"
    cp $seeds "$dir/corpus/"
    run_fuzzer "$dir/fuzz_$name" "$dir" "$seconds" -rss_limit_mb=2048 -max_len=8192
}
fuzz cache_file "$SRC/tests/cache_format/golden/*.sharc" "$FUZZ_SECONDS"
fuzz checkpoint_file "$SRC/tests/cache_format/golden/*.ckpt" "$CHECKPOINT_FUZZ_SECONDS"
echo "OK: sanitized tests passed; fuzzed caches ${FUZZ_SECONDS}s and checkpoints ${CHECKPOINT_FUZZ_SECONDS}s without a finding"
