#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Bake at scale from the command line: a bake killed (SIGKILL, SIGINT, SIGTERM) and resumed from its
# checkpoint gives the uninterrupted bake's cache byte for byte; damaged or mismatched checkpoints
# are refused; shards merge in any order to the same file; merge refuses mismatched inputs.
# Usage: scale_cli_test.sh SHARCBAKE SCENES_DIR WORK_DIR
set -u
sharcbake=$1
scenes=$2
work=$3
. "$(dirname "$0")/../cli_support.sh"

cornell="$scenes/cornell_box/cornell_box.gltf"
furnace="$scenes/furnace_rho050/furnace_rho050.gltf"
bake_args="--iterations 60 --resolution 320x180 --capacity 65536"
expect 0 "uninterrupted bake" "$sharcbake" bake "$cornell" -o "$work/full.sharc" $bake_args -q

# Starts the bake with a checkpoint every 2 iterations, waits for the first checkpoint, then
# sends SIGNAL after a random delay (0-0.15 s) so the kill lands at a different moment each run.
interrupt() {  # interrupt SIGNAL NAME
    signal=$1; name=$2
    rm -f "$work/$name.ckpt"
    "$sharcbake" bake "$cornell" -o "$work/$name.sharc" $bake_args -q --checkpoint "$work/$name.ckpt" \
        --checkpoint-interval 2 >"$work/$name.out" 2>&1 &
    pid=$!
    tries=0
    while [ ! -f "$work/$name.ckpt" ] && [ "$tries" -lt 600 ]; do sleep 0.05; tries=$((tries + 1)); done
    sleep "$(awk 'BEGIN { srand(); printf "%.2f", rand() * 0.15 }')"
    kill "-$signal" "$pid" 2>/dev/null || echo "note: the $name bake finished before the signal"
    wait "$pid"
    interrupted_code=$?
    [ -f "$work/$name.ckpt" ] || fail "$name: no checkpoint written"
}

interrupt KILL killed
expect 0 "resume after SIGKILL" "$sharcbake" bake "$cornell" -o "$work/killed.sharc" $bake_args -q --resume "$work/killed.ckpt"
cmp -s "$work/full.sharc" "$work/killed.sharc" || fail "the bake resumed after SIGKILL differs from the uninterrupted one"

interrupt INT interrupted
[ "$interrupted_code" -eq 130 ] || [ "$interrupted_code" -eq 0 ] || fail "SIGINT: exit $interrupted_code, expected 130"
if [ "$interrupted_code" -eq 130 ]; then
    expect 0 "the cache written on SIGINT is valid" "$sharcbake" validate "$work/interrupted.sharc"
    # (A signal during the last iteration lets the bake finish: stop_reason is then "iterations".)
    "$sharcbake" info "$work/interrupted.sharc" > "$work/info.txt"
    grep -q "iterations: 60" "$work/info.txt" || grep -q "stop_reason: interrupted" "$work/info.txt" ||
        fail "the cache written on SIGINT does not record stop_reason interrupted"
    echo "note: SIGINT stopped the bake after $(sed -n 's/^  iterations: //p' "$work/info.txt") of 60 iterations"
fi
expect 0 "resume after SIGINT" "$sharcbake" bake "$cornell" -o "$work/interrupted.sharc" $bake_args -q --resume "$work/interrupted.ckpt"
cmp -s "$work/full.sharc" "$work/interrupted.sharc" || fail "the bake resumed after SIGINT differs from the uninterrupted one"

# A second SIGINT while the first is honoured aborts at once, writing nothing; it said nothing
# either (exit 130 and an empty stderr). It says so now, and where the bake stands.
"$sharcbake" bake "$cornell" -o "$work/twice.sharc" --iterations 100000 --resolution 64x64 -q \
    --checkpoint "$work/twice.ckpt" 2> "$work/twice_err.txt" &
pid=$!
sleep 2
kill -INT "$pid"
sleep 0.4  # a person's second Ctrl-C; the same signal within 0.25 s is one request delivered twice
kill -INT "$pid" 2>/dev/null
wait "$pid"
twice_code=$?
[ "$twice_code" -eq 130 ] || fail "two SIGINTs: exit $twice_code, expected 130"
if [ -e "$work/twice.sharc" ]; then
    echo "note: the bake had written its cache before the second SIGINT"
else
    says "$work/twice_err.txt" "a second signal: aborted at once, no cache written" "the abort is said"
fi
# The abort removes the checkpoint's lock file (it used to stay behind as clutter).
[ ! -e "$work/twice.ckpt.lock" ] || fail "two SIGINTs left the checkpoint lock file behind"

# One request delivered twice: GNU timeout signals the bake, then its whole process group, the bake
# included. The second copy aborted the bake with nothing written (seen once in 20 runs on a loaded
# machine); the same signal within 0.25 s of the first is now the same request. Both ways of sending
# it: two kills back to back, and timeout itself.
"$sharcbake" bake "$cornell" -o "$work/dup.sharc" --iterations 100000 --resolution 64x64 -q 2> "$work/dup_err.txt" &
pid=$!
sleep 2
kill -INT "$pid"
kill -INT "$pid" 2>/dev/null
wait "$pid"
dup_code=$?
[ "$dup_code" -eq 130 ] || fail "one SIGINT delivered twice: exit $dup_code, expected 130"
[ -f "$work/dup.sharc" ] || fail "one SIGINT delivered twice aborted the bake: $(cat "$work/dup_err.txt")"
timeout --preserve-status -s INT 3 "$sharcbake" bake "$cornell" -o "$work/timeout.sharc" --iterations 100000 \
    --resolution 64x64 -q 2> "$work/timeout_err.txt"
timeout_code=$?
[ "$timeout_code" -eq 130 ] || fail "timeout -s INT: exit $timeout_code, expected 130: $(cat "$work/timeout_err.txt")"
expect 0 "the cache written under timeout -s INT is valid" "$sharcbake" validate "$work/timeout.sharc"

# SIGTERM (a scheduler's time limit or preemption): the same, with exit 143.
interrupt TERM terminated
[ "$interrupted_code" -eq 143 ] || [ "$interrupted_code" -eq 0 ] || fail "SIGTERM: exit $interrupted_code, expected 143"
expect 0 "resume after SIGTERM" "$sharcbake" bake "$cornell" -o "$work/terminated.sharc" $bake_args -q --resume "$work/terminated.ckpt"
cmp -s "$work/full.sharc" "$work/terminated.sharc" || fail "the bake resumed after SIGTERM differs from the uninterrupted one"

# A finished bake's checkpoint extends it: 40 + 20 iterations == 60 iterations.
expect 0 "bake 40 with a checkpoint" "$sharcbake" bake "$cornell" -o "$work/short.sharc" --iterations 40 --resolution 320x180 --capacity 65536 -q \
    --checkpoint "$work/short.ckpt"
expect 0 "extend it to 60" "$sharcbake" bake "$cornell" -o "$work/extended.sharc" $bake_args -q --resume "$work/short.ckpt"
cmp -s "$work/full.sharc" "$work/extended.sharc" || fail "40 + 20 iterations differ from 60"

# A resumed bake's summary says how many iterations this run baked, and its rays/s counts this run's
# rays alone: the checkpoint's rays over this run's time doubled the rate, and a resume that baked
# none reported 1.7e16 rays/s.
expect 0 "resume the extended checkpoint" "$sharcbake" bake "$cornell" -o "$work/again.sharc" $bake_args \
    --resume "$work/short.ckpt" --stats-json "$work/again.json"
says "$work/out.txt" "Baked 60 iterations, 0 of them in this run," "a resume says what this run baked"
python3 -c "import json, sys; r = json.load(open(sys.argv[1]))['rays_per_second']; sys.exit(r != 0)" "$work/again.json" ||
    fail "a resume that baked no iteration reports rays/s"

# Options that change what is made from the baked voxels but not the voxels (--voxel-materials,
# --prediction-views, ...) may differ on a resume: one warning line for each names the option and
# both values, and the bake goes on. A resume with the same values warns about none.
neutral_args="--resolution 32x32 --capacity 65536 -q"
expect 0 "bake 2 with a checkpoint" "$sharcbake" bake "$furnace" -o "$work/neutral.sharc" --iterations 2 $neutral_args \
    --checkpoint "$work/neutral.ckpt"
expect 0 "resume with other cache-neutral options" "$sharcbake" bake "$furnace" -o "$work/neutral.sharc" --iterations 4 \
    $neutral_args --resume "$work/neutral.ckpt" --voxel-materials --prediction-views 8
says "$work/err.txt" '^warning: .*neutral.ckpt: --voxel-materials: checkpoint "false", this bake "true"' \
    "the resume warns that --voxel-materials differs, with both values"
says "$work/err.txt" '^warning: .*neutral.ckpt: --prediction-views: checkpoint "32", this bake "8"' \
    "the resume warns that --prediction-views differs, with both values"
[ "$(grep -c 'checkpoint "' "$work/err.txt")" -eq 2 ] || fail "expected two warnings about the checkpoint's options"
expect 0 "info on the resumed bake" "$sharcbake" info "$work/neutral.sharc"
says "$work/out.txt" "iterations: 4" "the resume with other cache-neutral options baked"
expect 0 "resume with the same cache-neutral options" "$sharcbake" bake "$furnace" -o "$work/neutral.sharc" \
    --iterations 6 $neutral_args --resume "$work/neutral.ckpt" --voxel-materials --prediction-views 8
grep -q 'checkpoint "' "$work/err.txt" && fail "a resume with the checkpoint's own options warned: $(cat "$work/err.txt")"

# Refusals: other settings, a damaged checkpoint, a cache given as a checkpoint, a missing file.
expect 3 "resume with another seed" "$sharcbake" bake "$cornell" -o "$work/x.sharc" $bake_args --seed 7 -q --resume "$work/short.ckpt"
grep -q 'seed: checkpoint "0", this bake "7"' "$work/err.txt" || fail "the mismatch message does not name the setting"
expect 3 "resume with another light selection" "$sharcbake" bake "$cornell" -o "$work/x.sharc" $bake_args \
    --light-selection power -q --resume "$work/short.ckpt"
grep -q 'light_selection: checkpoint "auto", this bake "power"' "$work/err.txt" ||
    fail "the light selection mismatch is not named"
expect 3 "resume on another scene" "$sharcbake" bake "$furnace" -o "$work/x.sharc" $bake_args -q --resume "$work/short.ckpt"
cp "$work/short.ckpt" "$work/damaged.ckpt"
printf '\377' | dd of="$work/damaged.ckpt" bs=1 seek=200 conv=notrunc 2>/dev/null
expect 3 "resume from a damaged checkpoint" "$sharcbake" bake "$cornell" -o "$work/x.sharc" $bake_args -q --resume "$work/damaged.ckpt"
grep -q "checksum" "$work/err.txt" || fail "the damaged checkpoint's message does not say checksum"
expect 3 "resume from a cache file" "$sharcbake" bake "$cornell" -o "$work/x.sharc" $bake_args -q --resume "$work/full.sharc"
expect 2 "resume from a missing file" "$sharcbake" bake "$cornell" -o "$work/x.sharc" $bake_args -q --resume "$work/none.ckpt"

# Shards: four shares of the furnace, merged in two orders to the same bytes.
expect 1 "bad shard" "$sharcbake" bake "$furnace" -o "$work/x.sharc" --shard 4/4
expect 1 "bad shard syntax" "$sharcbake" bake "$furnace" -o "$work/x.sharc" --shard 1of4
for i in 0 1 2 3; do
    expect 0 "shard $i/4" "$sharcbake" bake "$furnace" -o "$work/shard$i.sharc" --iterations 8 --resolution 96x96 -q --shard "$i/4"
done
# A shard that checkpoints and resumes (a preempted job in a batch queue) ends with the shard's
# uninterrupted cache byte for byte.
expect 0 "shard with a checkpoint" "$sharcbake" bake "$furnace" -o "$work/shard1ck.sharc" --iterations 4 --resolution 96x96 -q --shard 1/4 --checkpoint "$work/shard1.ckpt"
expect 0 "shard resumed" "$sharcbake" bake "$furnace" -o "$work/shard1ck.sharc" --iterations 8 --resolution 96x96 -q --shard 1/4 --resume "$work/shard1.ckpt"
cmp -s "$work/shard1.sharc" "$work/shard1ck.sharc" || fail "the resumed shard differs from the uninterrupted one"
# Resuming with fewer --iterations than the checkpoint holds bakes none and says so.
expect 0 "resume with fewer iterations than the checkpoint" "$sharcbake" bake "$furnace" -o "$work/fewer.sharc" --iterations 4 --resolution 96x96 -q --shard 1/4 --resume "$work/shard1.ckpt"
says "$work/err.txt" "holds 8 iterations, more than --iterations 4" "the resume says it bakes no more"
cmp -s "$work/shard1.sharc" "$work/fewer.sharc" || fail "the cache of a resume with fewer iterations differs from the checkpoint's bake"
# Rerunning the first command (no --resume) would replace the checkpoint with a fresh bake's: refused.
cp "$work/shard1.ckpt" "$work/shard1.ckpt.before"
expect 1 "a fresh bake onto an existing checkpoint" "$sharcbake" bake "$furnace" -o "$work/shard1ck.sharc" --iterations 4 --resolution 96x96 -q --shard 1/4 --checkpoint "$work/shard1.ckpt"
says "$work/err.txt" "add --resume" "the refusal says how to continue"
cmp -s "$work/shard1.ckpt" "$work/shard1.ckpt.before" || fail "the refused bake changed the checkpoint"
expect 3 "resume a shard's checkpoint as another shard" "$sharcbake" bake "$furnace" -o "$work/x.sharc" --iterations 8 --resolution 96x96 -q --shard 2/4 --resume "$work/shard1.ckpt"
expect 0 "merge" "$sharcbake" merge "$work/shard0.sharc" "$work/shard1.sharc" "$work/shard2.sharc" "$work/shard3.sharc" -o "$work/merged.sharc"
expect 0 "merge in another order" "$sharcbake" merge "$work/shard2.sharc" "$work/shard0.sharc" "$work/shard3.sharc" "$work/shard1.sharc" -o "$work/merged2.sharc" -q
cmp -s "$work/merged.sharc" "$work/merged2.sharc" || fail "the merge depends on the order of its inputs"
expect 0 "info on the merge" "$sharcbake" info "$work/merged.sharc"
grep -q "merged_shards: 0/4,1/4,2/4,3/4" "$work/out.txt" || fail "the merged cache does not list its shards"
grep -q "iterations: 32" "$work/out.txt" || fail "the merged cache does not sum the iterations"

expect 0 "merge with a shard missing" "$sharcbake" merge "$work/shard0.sharc" "$work/shard1.sharc" "$work/shard3.sharc" -o "$work/partial.sharc"
grep -q "1 of 4 shards missing (2/4)" "$work/err.txt" || fail "merge does not warn about the missing shard 2/4"

# Merge refusals: another scene, other grid parameters, the same shard twice, not a cache.
expect 3 "merge different scenes" "$sharcbake" merge "$work/shard0.sharc" "$work/full.sharc" -o "$work/x.sharc"
grep -q "scene_hash" "$work/err.txt" || fail "the scene mismatch message does not name scene_hash"
expect 0 "shard with another scene scale" "$sharcbake" bake "$furnace" -o "$work/coarse.sharc" --iterations 2 --resolution 64x64 -q --shard 1/4 --scene-scale 10
expect 3 "merge different grids" "$sharcbake" merge "$work/shard0.sharc" "$work/coarse.sharc" -o "$work/x.sharc"
grep -q "scene scale" "$work/err.txt" || fail "the grid mismatch message does not name the parameter"
expect 0 "shard under another sky" "$sharcbake" bake "$furnace" -o "$work/sky.sharc" --iterations 2 --resolution 64x64 -q --shard 1/4 --sky 0.5,0.5,0.5
expect 3 "merge different skies" "$sharcbake" merge "$work/shard0.sharc" "$work/sky.sharc" -o "$work/x.sharc"
grep -q '"sky" differs' "$work/err.txt" || fail "the sky mismatch message does not name the sky"
expect 3 "merge the same shard twice" "$sharcbake" merge "$work/shard0.sharc" "$work/shard0.sharc" -o "$work/x.sharc"
# Bakes of one --seed draw the same samples for the same iteration: a 2- and a 3-iteration bake of
# seed 0 merged into "5 iterations", two of them counted twice; so did a bake beside a shard of its
# seed (shard 1/4's iteration 0 is the bake's iteration 1). Other seeds are independent samples.
expect 0 "unsharded, 2 iterations" "$sharcbake" bake "$furnace" -o "$work/two.sharc" --iterations 2 --resolution 96x96 -q
expect 0 "unsharded, 3 iterations" "$sharcbake" bake "$furnace" -o "$work/three.sharc" --iterations 3 --resolution 96x96 -q
expect 3 "merge two bakes of one seed" "$sharcbake" merge "$work/two.sharc" "$work/three.sharc" -o "$work/x.sharc"
says "$work/err.txt" "were both baked with --seed 0 and both ran iteration 0" "the refusal names the seed and the iteration"
expect 3 "merge a bake with a shard of its seed" "$sharcbake" merge "$work/two.sharc" "$work/shard1.sharc" -o "$work/x.sharc"
says "$work/err.txt" "both ran iteration 1" "the shard's first iteration is named in the unsharded numbering"
expect 0 "merge a bake with shard 2/4, which it never reached" "$sharcbake" merge "$work/two.sharc" "$work/shard2.sharc" -o "$work/x.sharc" -q
expect 0 "another seed" "$sharcbake" bake "$furnace" -o "$work/seed7.sharc" --iterations 3 --resolution 96x96 -q --seed 7
expect 0 "merge bakes of different seeds" "$sharcbake" merge "$work/two.sharc" "$work/seed7.sharc" -o "$work/x.sharc" -q
# Merges of merges: a merged cache and one of its own shards counted that shard twice (exit 0); two
# merged caches failed on a duplicate metadata key; shards split different ways merged silently.
expect 0 "merge half" "$sharcbake" merge "$work/shard0.sharc" "$work/shard1.sharc" -o "$work/half01.sharc" -q
expect 0 "merge the other half" "$sharcbake" merge "$work/shard2.sharc" "$work/shard3.sharc" -o "$work/half23.sharc" -q
expect 3 "merge a merge with one of its shards" "$sharcbake" merge "$work/half01.sharc" "$work/shard0.sharc" -o "$work/x.sharc"
says "$work/err.txt" "both hold the same bake" "merge names the bake held twice"
expect 0 "merge two merges" "$sharcbake" merge "$work/half01.sharc" "$work/half23.sharc" -o "$work/tree.sharc"
expect 0 "info on the tree merge" "$sharcbake" info "$work/tree.sharc"
says "$work/out.txt" "merged_shards: 0/4,1/4,2/4,3/4" "the tree merge lists every shard"
says "$work/out.txt" "merged_inputs: 4" "the tree merge counts the bakes"
expect 0 "merge a merge with the remaining shards" "$sharcbake" merge "$work/half01.sharc" "$work/shard2.sharc" "$work/shard3.sharc" -o "$work/mixed.sharc" -q
expect 0 "info on that merge" "$sharcbake" info "$work/mixed.sharc"
says "$work/out.txt" "merged_shards: 0/4,1/4,2/4,3/4" "a merge of a merge and shards lists every shard"
expect 0 "a shard of another split" "$sharcbake" bake "$furnace" -o "$work/third.sharc" --iterations 8 --resolution 64x64 --capacity 65536 --shard 1/3 -q
expect 3 "merge shards split different ways" "$sharcbake" merge "$work/shard0.sharc" "$work/third.sharc" -o "$work/x.sharc"
says "$work/err.txt" "shard counts 3, 4" "merge names the shard counts"
expect 3 "merge a checkpoint" "$sharcbake" merge "$work/shard0.sharc" "$work/short.ckpt" -o "$work/x.sharc"
grep -q "checkpoint" "$work/err.txt" || fail "merge does not say that the input is a checkpoint"
expect 3 "info on a checkpoint" "$sharcbake" info "$work/short.ckpt"
grep -q "bake --resume" "$work/err.txt" || fail "info does not say how to use a checkpoint"
expect 2 "merge a missing file (an I/O error, as the README's table says)" "$sharcbake" merge "$work/shard0.sharc" "$work/none.sharc" -o "$work/x.sharc"

# --capacity auto: a table sized from the scene, and info reports what the bake left out.
expect 1 "bad capacity" "$sharcbake" bake "$furnace" -o "$work/x.sharc" --capacity lots
expect 1 "capacity below a bucket" "$sharcbake" bake "$furnace" -o "$work/x.sharc" --capacity 8
expect 0 "bake with --capacity auto" "$sharcbake" bake "$cornell" -o "$work/auto.sharc" --iterations 8 --resolution 160x90 --capacity auto
# 16 iterations sampled over the 64-waypoint loop, whatever --iterations (here 8).
grep -q "Capacity auto: 262144 slots to start" "$work/out.txt" || fail "auto capacity: expected 262144 slots for this Cornell bake"
expect 0 "info on the auto bake" "$sharcbake" info "$work/auto.sharc"
grep -q "Left out by the bake: sky lookups and sky sampling (black sky); texture fetches and UV interpolation (no textures)" \
    "$work/out.txt" || fail "info does not report what the Cornell bake left out"
grep -q "Table capacity auto: 262144 slots" "$work/out.txt" || fail "info does not report the auto capacity"
expect 0 "the same bake with a fixed capacity" "$sharcbake" bake "$cornell" -o "$work/fixed.sharc" --iterations 8 --resolution 160x90 --capacity 65536 -q
# The voxels (KEYS and VOXL sections, compared by their CRC-32s) do not depend on the capacity.
for f in auto fixed; do
    "$sharcbake" info "$work/$f.sharc" --json | python3 -c "
import json, sys
print(sorted((s['type'], s['crc32']) for s in json.load(sys.stdin)['sections'] if s['type'] in ('KEYS', 'VOXL')))" \
        > "$work/$f.voxels"
done
cmp -s "$work/auto.voxels" "$work/fixed.voxels" || fail "--capacity auto changed the baked voxels"
# A bake split by a checkpoint and a resume with more --iterations records the uninterrupted bake's
# capacity_choice: the pre-pass samples one loop of the camera path, never --iterations, so the
# two files are the same byte for byte.
auto_args="--resolution 64x64 --capacity auto -q"
expect 0 "an auto-capacity bake of 16 iterations" "$sharcbake" bake "$furnace" -o "$work/auto16.sharc" --iterations 16 $auto_args
expect 0 "the same bake, 8 iterations with a checkpoint" "$sharcbake" bake "$furnace" -o "$work/auto8.sharc" \
    --iterations 8 $auto_args --checkpoint "$work/auto8.ckpt"
expect 0 "resumed to 16 iterations" "$sharcbake" bake "$furnace" -o "$work/auto8.sharc" --iterations 16 $auto_args \
    --resume "$work/auto8.ckpt"
cmp -s "$work/auto16.sharc" "$work/auto8.sharc" ||
    fail "--capacity auto: 8 + 8 resumed iterations differ from 16 ($("$sharcbake" info "$work/auto16.sharc" |
        grep capacity_choice) / $("$sharcbake" info "$work/auto8.sharc" | grep capacity_choice))"

finish "bake at scale"
