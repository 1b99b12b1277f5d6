#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# `bake --gpu-radiance-scale`: recorded in the cache (RSCL, cache_format/SPEC.md F.8a), shown by
# `info`, and a warning with the factor that fits when a GPU table's fp16 would clip (SPEC G.6).
# Usage: gpu_scale_cli_test.sh SHARCBAKE SCENES_DIR WORK_DIR
set -u
sharcbake=$1
scenes=$2
work=$3
. "$(dirname "$0")/../cli_support.sh"
scene="$scenes/cornell_box/cornell_box.gltf"
small="--iterations 2 --resolution 32x32 -q"

expect 0 "bake at scale 1" "$sharcbake" bake "$scene" -o "$work/plain.sharc" $small
expect 0 "info" "$sharcbake" info "$work/plain.sharc"
says "$work/out.txt" "radiance x 1 (no RSCL section), fp16 up to 65504: nothing clips" "scale 1 writes no RSCL"

expect 0 "bake at scale 0.5" "$sharcbake" bake "$scene" -o "$work/half.sharc" $small --gpu-radiance-scale 0.5
expect 0 "info" "$sharcbake" info "$work/half.sharc"
says "$work/out.txt" "radiance x 0.5 (RSCL section)" "info shows the recorded scale"
says "$work/out.txt" "format 1.2" "the cache is format 1.2"
expect 0 "info --json" "$sharcbake" info "$work/half.sharc" --json
python3 - "$work/out.txt" <<'PY' || fail "info --json gpu fields"
import json, sys
g = json.load(open(sys.argv[1]))["gpu"]
assert g["radiance_scale"] == 0.5 and g["clipped_voxels"] == 0 and g["fitting_radiance_scale"] > 0.5, g
PY

expect 0 "bake at a scale that clips" "$sharcbake" bake "$scene" -o "$work/bright.sharc" $small --gpu-radiance-scale 1e9
says "$work/err.txt" "warning: GPU buffers: .* voxels have a channel above fp16's 65504 after radiance scale 1e+09" \
    "the bake warns about clipping"
says "$work/err.txt" "a radiance scale of .* or less keeps them" "the warning names the scale that fits"

# --voxel-materials: a VMAT section of 24 bytes per voxel, which info reports.
expect 0 "info" "$sharcbake" info "$work/plain.sharc"
says "$work/out.txt" "Voxel materials: not kept" "a plain bake keeps no voxel materials"
expect 0 "bake --voxel-materials" "$sharcbake" bake "$scene" -o "$work/materials.sharc" --iterations 2 --resolution 32x32 \
    --voxel-materials
says "$work/out.txt" "voxel materials (emission, demodulation factor) from [0-9]* surface points" "the bake says so"
expect 0 "info" "$sharcbake" info "$work/materials.sharc" --json
python3 - "$work/out.txt" "$work/plain.sharc" "$work/materials.sharc" <<'PY' || fail "VMAT in the file"
import json, os, sys
info = json.load(open(sys.argv[1]))
assert info["gpu"]["voxel_materials"] is True, info["gpu"]
vmat = [s for s in info["sections"] if s["type"] == "VMAT"]
assert len(vmat) == 1 and not vmat[0]["required"] and vmat[0]["length"] == 24 * info["voxels"], vmat
PY

expect 1 "scale 0 is refused" "$sharcbake" bake "$scene" -o "$work/zero.sharc" $small --gpu-radiance-scale 0
expect 1 "a negative scale is refused" "$sharcbake" bake "$scene" -o "$work/neg.sharc" $small --gpu-radiance-scale -2
# The fixed-point radiance scale in the metadata: a light of 1e20 makes it 2^-27, which six
# decimals wrote as 0.000000; ordinary scenes (scale 1 and more) keep their bytes.
mkdir -p "$work/bright"
cp "$scenes/cornell_box/cornell_box.bin" "$work/bright/"
python3 - "$scene" "$work/bright/cornell_box.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
for m in g["materials"]:
    if m.get("emissiveFactor", [0, 0, 0]) != [0, 0, 0]:
        m.setdefault("extensions", {})["KHR_materials_emissive_strength"] = {"emissiveStrength": 1e20}
g.setdefault("extensionsUsed", []).append("KHR_materials_emissive_strength")
json.dump(g, open(sys.argv[2], "w"))
PY
expect 0 "bake a 1e20 light" "$sharcbake" bake "$work/bright/cornell_box.gltf" -o "$work/bright.sharc" $small
expect 0 "info of the bright cache" "$sharcbake" info "$work/bright.sharc"
says "$work/out.txt" "radiance_scale: [0-9.]*e-[0-9]*$" "a scale below 1 keeps its digits"
expect 0 "info of the plain cache" "$sharcbake" info "$work/plain.sharc"
says "$work/out.txt" "radiance_scale: [0-9]*\.000000$" "a scale of 1 or more is written as before"
finish gpu_scale_cli_test
