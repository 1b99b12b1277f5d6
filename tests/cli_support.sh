# SPDX-License-Identifier: Apache-2.0
# Shared by the command-line test scripts (sourced, POSIX sh). Each script sets `sharcbake`,
# `scenes` and `work` from its arguments, then sources this file, which empties WORK_DIR and
# defines:
#   fail TEXT...                     count a failure and say what failed
#   expect CODE DESCRIPTION CMD...   run CMD (stdout to $work/out.txt, stderr to $work/err.txt)
#                                    and check its exit code; on a mismatch, show both outputs
#   says FILE TEXT DESCRIPTION       check that FILE contains TEXT
#   finish NAME                      print the outcome and exit non-zero after any failure
rm -rf "$work" && mkdir -p "$work"
failures=0

fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

expect() {
    code=$1; what=$2; shift 2
    "$@" >"$work/out.txt" 2>"$work/err.txt"
    got=$?
    if [ "$got" -ne "$code" ]; then
        fail "$what: exit $got, expected $code"; cat "$work/out.txt" "$work/err.txt"
    else
        echo "ok: $what (exit $got)"
    fi
}

says() {
    if grep -q -- "$2" "$1"; then echo "ok: $3"; else fail "$3: no \"$2\" in:"; cat "$1"; fi
}

finish() {
    if [ "$failures" -ne 0 ]; then echo "$1: $failures failure(s)"; exit 1; fi
    echo "$1: all checks passed"
    exit 0
}
