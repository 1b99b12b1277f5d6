#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# The README's GNU parallel recipe for shards, run for real: its two command lines are taken from
# the README, scaled down (4 shards of a small bake instead of 16 of 256 iterations), run with GNU
# parallel two at a time, and merged. The shards must equal the same shards baked one after the
# other (so scheduling cannot change a result), and the merge must hold all four.
# Usage: parallel_shards_test.sh SHARCBAKE SCENES_DIR WORK_DIR README
set -u
sharcbake=$1
scenes=$2
work=$3
readme=$4
. "$(dirname "$0")/../cli_support.sh"

command -v parallel >/dev/null || { echo "FAIL: GNU parallel is not installed (Debian package 'parallel')"; exit 1; }
bake_line=$(grep '^parallel sharcbake bake' "$readme")
merge_line=$(grep -A1 '^parallel sharcbake bake' "$readme" | grep '^sharcbake merge')
[ -n "$bake_line" ] && [ -n "$merge_line" ] || { echo "FAIL: the README has no GNU parallel recipe"; exit 1; }
echo "README: $bake_line"
echo "README: $merge_line"

# The recipe's names and sizes, scaled down; everything else as written.
scale() {
    printf '%s\n' "$1" | sed -e "s|level\.gltf|$scenes/cornell_box/cornell_box.gltf|" \
        -e 's|--iterations 256|--iterations 6 --resolution 160x90 --capacity 65536|' \
        -e 's|/16 |/4 |' -e 's|\$(seq 0 15)|$(seq 0 3)|' -e 's|^parallel |parallel --jobs 2 --halt now,fail=1 |'
}
mkdir -p "$work/run/shards" && rm -f "$work/run/shards/"* "$work/run/level.sharc"
PATH="$(dirname "$sharcbake"):$PATH"
export PATH
expect 0 "the README's parallel bake, scaled down" sh -c "cd '$work/run' && $(scale "$bake_line")"
expect 0 "the README's merge" sh -c "cd '$work/run' && $(scale "$merge_line")"
expect 0 "info of the merge" "$sharcbake" info "$work/run/level.sharc"
says "$work/out.txt" "merged_shards: 0/4,1/4,2/4,3/4" "the merge holds the four shards"

for i in 0 1 2 3; do
    "$sharcbake" bake "$scenes/cornell_box/cornell_box.gltf" --iterations 6 --resolution 160x90 --capacity 65536 \
        --shard "$i/4" -o "$work/sequential.$i.sharc" -q 2>/dev/null
    cmp -s "$work/sequential.$i.sharc" "$work/run/shards/level.$i.sharc" ||
        fail "shard $i baked under GNU parallel differs from the same shard baked alone"
done
echo "ok: shards baked in parallel equal shards baked one after the other"

finish "GNU parallel shards"
