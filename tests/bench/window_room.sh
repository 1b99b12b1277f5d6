#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Default bakes of a room with a window on a lawn 200 m wide, built and exported by Blender
# (window_room.py), lit by a sun through the window, a lamp or a ceiling panel: each baked with the
# default region (auto) and with --view-region free, rendered through the cache from the room's own
# cameras and measured against a path-traced reference (BENCHMARKS.md, "A room with a window on a
# lawn"). Not part of `make test` (it needs Blender: `apt-get install blender`). About 15 minutes
# on 2 cores.
# Usage: tests/bench/window_room.sh SHARCBAKE WORK_DIR [REFERENCE_SPP] [LIGHTS]
# (LIGHTS: a space-separated list of sun, lamp, panel; all three unless given)
set -eu
sharcbake=$1
work=$2
spp=${3:-1024}
lights=${4:-sun lamp panel}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$work"

measure() {  # measure IMAGE REFERENCE: relative MSE (relative bias)
    "$sharcbake" compare --json "$1" "$2" |
        python3 -c 'import json,sys; d=json.load(sys.stdin); print("%.3g (%+.1f%%)" % (d["relative_mse"], 100 * d["relative_bias"]))'
}

for light in $lights; do
    scene="$work/$light.glb"
    # Blender exits 0 when the script raises: the file is what says it worked.
    [ -e "$scene" ] || blender -b --factory-startup --python "$here/window_room.py" -- "$scene" "$light" \
        > "$work/$light.blender.log" 2>&1
    [ -e "$scene" ] || { tail -20 "$work/$light.blender.log"; exit 1; }
    for region in auto free; do
        "$sharcbake" bake "$scene" -o "$work/$light.$region.sharc" --view-region "$region" > "$work/$light.$region.log" 2>&1
        echo "$light, $region: $(grep -o 'finest voxels [0-9.e+-]* wide' "$work/$light.$region.log"), $(grep -o '[0-9]* live voxels' "$work/$light.$region.log"), $(grep -o 'Baked [0-9]* iterations in [0-9.]* s' "$work/$light.$region.log"), $(grep -o 'segments [0-9]*' "$work/$light.$region.log")"
    done
    for camera in "Camera" "Window view"; do
        name=$(echo "$light.$camera" | tr ' ' '_')
        [ -e "$work/$name.reference.exr" ] || "$sharcbake" render "$scene" --camera "$camera" \
            -o "$work/$name.reference.exr" --resolution 256 --spp "$spp" --no-png -q
        "$sharcbake" render "$scene" --camera "$camera" -o "$work/$name.path_traced.exr" --resolution 256 --spp 64 --no-png -q
        line="$light, $camera: path tracing 64 spp $(measure "$work/$name.path_traced.exr" "$work/$name.reference.exr")"
        for region in auto free; do
            "$sharcbake" render "$scene" --camera "$camera" -o "$work/$name.$region.exr" --resolution 256 --spp 64 \
                --no-png -q --cache "$work/$light.$region.sharc"
            line="$line; cached 64 spp, $region $(measure "$work/$name.$region.exr" "$work/$name.reference.exr")"
        done
        echo "$line"
    done
done
