#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Cross-check against another renderer: Blender's Cycles renders a room built in Blender (see
# cycles_room.py), sharcbake renders the same room from Blender's glTF export, with plain path
# tracing and through a cache baked with default settings, and `sharcbake compare` measures both
# against Cycles. Not part of `make test` (it needs Blender: `apt-get install blender`, about
# 1 GB); results are in docs/notes/cycles_crosscheck.md.
# Usage: tests/crosscheck/cycles_crosscheck.sh SHARCBAKE WORK_DIR [CYCLES_SAMPLES] [SHARCBAKE_SPP]
set -eu
sharcbake=$1
work=$2
cycles_samples=${3:-2048}
spp=${4:-1024}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$work"

blender -b --factory-startup --python "$here/cycles_room.py" -- "$work" "$cycles_samples" > "$work/blender.log" 2>&1 ||
    { tail -20 "$work/blender.log"; exit 1; }

"$sharcbake" render "$work/room.glb" -o "$work/path_traced.exr" --resolution 96x96 --spp "$spp" -q
"$sharcbake" bake "$work/room.glb" -o "$work/room.sharc" > "$work/bake.log"
grep -E "Camera:|predicted hit rate|camera '" "$work/bake.log"
"$sharcbake" render "$work/room.glb" -o "$work/cached.exr" --resolution 96x96 --spp "$((spp / 4))" \
    --cache "$work/room.sharc" -q

echo "path tracing ($spp spp) against Cycles ($cycles_samples samples):"
"$sharcbake" compare "$work/path_traced.exr" "$work/cycles.exr"
echo "through the cache ($((spp / 4)) spp) against Cycles:"
"$sharcbake" compare "$work/cached.exr" "$work/cycles.exr"
echo "Cycles' multilayer file against its plain one (must be identical):"
"$sharcbake" compare "$work/cycles_multilayer.exr" "$work/cycles.exr"
