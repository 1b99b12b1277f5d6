# SPDX-License-Identifier: Apache-2.0
# Shared by the scripts that run libFuzzer harnesses (sourced, bash). Defines:
#   run_fuzzer BINARY DIR SECONDS [LIBFUZZER_OPTION...]
#       runs BINARY over every input in DIR/corpus once (the seeds as a plain regression run),
#       then fuzzes for SECONDS with the options given (and a 10 s limit per input), reproducers
#       going to DIR/artifacts/; prints libFuzzer's run statistics. Any crash, sanitizer report,
#       leak, timeout or reproducer exits the calling script with 1, showing the log's end.
#       The search is seeded with FUZZ_SEED (default 1), so that every test run mutates along
#       the same sequence (as far as its time allows) and a failure in CI reproduces here;
#       FUZZ_SEED=0 draws a new seed each run (libFuzzer's default), for longer searches by hand:
#       FUZZ_SEED=0 IMAGE_FUZZ_SECONDS=600 tests/scenes/fuzzed_loaders_test.sh . /tmp/f build/bin/sharcbake
run_fuzzer() {
    local binary=$1 dir=$2 seconds=$3 name
    name=$(basename "$binary")
    shift 3
    # The harnesses' scratch files go to the work folder, not /tmp: a crash leaves them behind.
    mkdir -p "$dir/artifacts" "$dir/tmp"
    export TMPDIR="$dir/tmp"
    "$binary" -runs=0 "$dir/corpus" >"$dir/seeds.log" 2>&1 || {
        tail -n 60 "$dir/seeds.log"
        echo "FAIL: $name fails on a seed of $dir/corpus"
        exit 1
    }
    set +e
    "$binary" "$dir/corpus" "$@" -max_total_time="$seconds" -seed="${FUZZ_SEED:-1}" -timeout=10 -print_final_stats=1 \
        -artifact_prefix="$dir/artifacts/" >"$dir/fuzz.log" 2>&1
    local rc=$?
    set -e
    grep -E '^(stat::|Done )' "$dir/fuzz.log" || true
    if [ $rc -ne 0 ] || ls "$dir/artifacts/" | grep -q .; then
        tail -n 60 "$dir/fuzz.log"
        echo "FAIL: $name found a problem (exit $rc); reproducer(s) in $dir/artifacts/:"
        ls -l "$dir/artifacts/"
        exit 1
    fi
}
