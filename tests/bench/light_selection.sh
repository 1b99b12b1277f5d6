#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Light selection benchmark (BENCHMARKS.md): the error of path-traced images and of cached renders
# against converged references, in scenes where selection by power spends its shadow rays on
# lights a point cannot see (light_selection_scenes.py), and in the shipped outdoor scene, where
# power is nearly right. Prints one line per measure for each sharcbake given, so a build before
# a change and one after can be compared in one run:
#
#   tests/bench/light_selection.sh WORK_DIR build/bin/sharcbake [OTHER_SHARCBAKE ...]
#
# The references are rendered by the last sharcbake given, the newest: every version renders the
# same expected image, but by power a lamp in flat_on_ground is picked 1e-8 of the time, so an
# older version's 16384 samples per pixel leave its light all but missing. A few minutes per
# sharcbake on 2 cores.
set -eu
work=$1
shift
here=$(cd "$(dirname "$0")" && pwd)
scenes=$(cd "$here/../../scenes" && pwd)
mkdir -p "$work"
python3 "$here/light_selection_scenes.py" "$work"
for reference; do :; done

error() {  # error IMAGE REFERENCE: the relative MSE
    "$reference" compare --json "$1" "$2" | python3 -c 'import json,sys; print("%.3g" % json.load(sys.stdin)["relative_mse"])'
}

# name scene camera: the reference, 24x24 at 16384 spp
views="thin_walls $work/thin_walls.gltf room_b
flat_room_1 $work/flat.gltf room_1
flat_room_2 $work/flat.gltf room_2
flat_room_3 $work/flat.gltf room_3
flat_on_ground_room_1 $work/flat_on_ground.gltf room_1
flat_on_ground_room_2 $work/flat_on_ground.gltf room_2
flat_on_ground_room_3 $work/flat_on_ground.gltf room_3
outdoor $scenes/outdoor/outdoor.gltf camera"
echo "$views" | while read -r name scene camera; do
    [ -e "$work/$name.reference.exr" ] ||
        "$reference" render "$scene" --camera "$camera" -o "$work/$name.reference.exr" --no-png --resolution 24 \
            --spp 16384 -q
done

for sharcbake in "$@"; do
    echo "== $sharcbake"
    echo "$views" | while read -r name scene camera; do
        start=$(date +%s.%N)
        "$sharcbake" render "$scene" --camera "$camera" -o "$work/$name.pt.exr" --no-png --resolution 24 --spp 256 -q
        seconds=$(awk "BEGIN { printf \"%.2f\", $(date +%s.%N) - $start }")
        echo "$name: path tracing 256 spp: relative MSE $(error "$work/$name.pt.exr" "$work/$name.reference.exr") ($seconds s)"
    done
    for scene in thin_walls flat flat_on_ground; do
        for iterations in 32 128 512; do
            start=$(date +%s.%N)
            "$sharcbake" bake "$work/$scene.gltf" -o "$work/$scene.sharc" --iterations "$iterations" -q
            seconds=$(awk "BEGIN { printf \"%.2f\", $(date +%s.%N) - $start }")
            echo "$views" | awk -v file="$work/$scene.gltf" '$2 == file' | while read -r name file camera; do
                "$sharcbake" render "$file" --camera "$camera" -o "$work/$name.cached.exr" --no-png --resolution 24 \
                    --spp 1024 --cache "$work/$scene.sharc" -q
                echo "$name: bake of $iterations iterations ($seconds s), cached render: relative MSE" \
                    "$(error "$work/$name.cached.exr" "$work/$name.reference.exr")"
            done
        done
    done
done
