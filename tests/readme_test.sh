#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Every command of the README, run in order as a new user would: each ```sh block is run from a
# folder laid out like the repository's root (build/bin/sharcbake, scenes/), and must succeed.
# Skipped: `make` lines (the two contract commands; this test is itself run by `make test`) and
# blocks the README marks <!-- readme-test: skip (reason) -->, each named in the output.
# Usage: readme_test.sh README SHARCBAKE SCENES_DIR WORK_DIR
set -u
readme=$1
sharcbake=$2
scenes=$3
work=$4

rm -rf "$work" && mkdir -p "$work/build/bin" || exit 1
ln -s "$sharcbake" "$work/build/bin/sharcbake"
ln -s "$scenes" "$work/scenes"

# Splits the README into block-NN.sh files, in order; a skipped block becomes block-NN.skip.
awk -v dir="$work" '
    /^<!-- readme-test: skip/ { skip = 1; reason = $0; next }
    /^```sh$/ { n++; file = sprintf("%s/block-%02d.%s", dir, n, skip ? "skip" : "sh"); inside = 1;
                if (skip) print reason > file; skip = 0; next }
    /^```/ && inside { inside = 0; close(file); next }
    inside && !/^make / { print > file }
    !inside && !/^[[:space:]]*$/ { skip = skip && /^<!--/ }
' "$readme"

blocks=0
failures=0
for block in "$work"/block-*; do
    case "$block" in
    *.skip) echo "skipped $(basename "$block"): $(head -1 "$block")"; continue ;;
    esac
    [ -s "$block" ] || continue  # only `make` lines
    blocks=$((blocks + 1))
    echo "== $(basename "$block")"
    cat "$block"
    if (cd "$work" && sh -e "$block" >"$block.out" 2>&1); then
        echo "ok"
    else
        echo "FAIL: $(basename "$block") exited $?:"
        tail -20 "$block.out"
        failures=$((failures + 1))
    fi
done
[ "$blocks" -ge 5 ] || { echo "FAIL: only $blocks runnable blocks found in $readme"; exit 1; }
if [ "$failures" -ne 0 ]; then echo "README: $failures of $blocks blocks failed"; exit 1; fi
echo "README: all $blocks blocks ran"
