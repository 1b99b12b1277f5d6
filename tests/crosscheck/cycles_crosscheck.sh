#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Cross-check against another renderer: Blender's Cycles renders a room built in Blender (see
# cycles_room.py; a diffuse room, then one with rough metals), sharcbake renders the same room
# from Blender's glTF export, with plain path tracing and through a cache baked with default
# settings, and `sharcbake compare` measures both against Cycles. Not part of `make test` (it needs Blender: `apt-get install blender`, about
# 1 GB); results are in docs/notes/cycles_crosscheck.md.
# Usage: tests/crosscheck/cycles_crosscheck.sh SHARCBAKE WORK_DIR [CYCLES_SAMPLES] [SHARCBAKE_SPP]
set -eu
sharcbake=$1
work=$2
cycles_samples=${3:-2048}
spp=${4:-1024}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$work"

for mode in diffuse metal; do
    dir="$work/$mode"
    mkdir -p "$dir"
    echo "== $mode room"
    blender -b --factory-startup --python "$here/cycles_room.py" -- "$dir" "$cycles_samples" "$mode" \
        > "$dir/blender.log" 2>&1 || { tail -20 "$dir/blender.log"; exit 1; }

    "$sharcbake" render "$dir/room.glb" -o "$dir/path_traced.exr" --resolution 96x96 --spp "$spp" -q 2> /dev/null
    "$sharcbake" bake "$dir/room.glb" -o "$dir/room.sharc" > "$dir/bake.log" 2>&1
    grep -E "Camera:|predicted hit rate|camera '" "$dir/bake.log"
    "$sharcbake" render "$dir/room.glb" -o "$dir/cached.exr" --resolution 96x96 --spp "$((spp / 4))" \
        --cache "$dir/room.sharc" -q 2> /dev/null

    echo "path tracing ($spp spp) against Cycles ($cycles_samples samples):"
    "$sharcbake" compare "$dir/path_traced.exr" "$dir/cycles.exr"
    echo "through the cache ($((spp / 4)) spp) against Cycles:"
    "$sharcbake" compare "$dir/cached.exr" "$dir/cycles.exr"
    echo "Cycles' multilayer file against its plain one (must be identical):"
    "$sharcbake" compare "$dir/cycles_multilayer.exr" "$dir/cycles.exr"
done
