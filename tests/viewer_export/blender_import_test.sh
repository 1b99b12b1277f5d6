#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# The Blender import script (viewer_export/blender/import_sharc_vdb.py) run headless on a real
# bake's VDB: the Cornell box must render upright (its lamp in the upper part of the image, as the
# glTF camera sees it), lit, with the red wall on the left and the green wall on the right.
# Skipped (exit 77) when Blender is not installed (Debian: blender).
# Usage: blender_import_test.sh SHARCBAKE SCENES_DIR SCRIPT WORK_DIR
set -u
sharcbake=$1
scenes=$2
script=$3
work=$4
. "$(dirname "$0")/../cli_support.sh"

command -v blender >/dev/null || { echo "skipped: blender is not installed"; exit 77; }
expect 0 "bake" "$sharcbake" bake "$scenes/cornell_box/cornell_box.gltf" -o "$work/cornell.sharc" --iterations 64 \
    --resolution 320x180 -q
expect 0 "export the finest level" "$sharcbake" export-vdb "$work/cornell.sharc" -o "$work/cornell.vdb" --levels 1 -q
expect 0 "Blender imports and renders it" blender -b --factory-startup --python "$script" -- "$work/cornell.vdb" \
    --render "$work/blender.png" --resolution 96
grep '^sharcbake_vdb_render: ' "$work/out.txt" | sed 's/^sharcbake_vdb_render: //' > "$work/render.json"
python3 - "$work/render.json" <<'PY' || fail "the Blender render"
import json, sys
r = json.load(open(sys.argv[1]))
print("render:", r)
left, right = r["left_rgb"], r["right_rgb"]
checks = {
    "most of the image is lit (the import has a material)": r["lit_fraction"] > 0.5,
    "red wall on the left": left[0] > 1.5 * left[1],
    "green wall on the right": right[1] > right[0],
    "upright: the lamp's white pixels in the upper part": r["white_from_top"] is not None and r["white_from_top"] < 0.4,
}
for what, ok in checks.items():
    print(("ok: " if ok else "FAIL: ") + what)
sys.exit(0 if all(checks.values()) else 1)
PY
# Exported in millimetres (a volume 1000x larger than Blender's default far clip of 1000 units
# reaches): the still was black. The camera's clip range follows the volume now.
expect 0 "export in millimetres" "$sharcbake" export-vdb "$work/cornell.sharc" -o "$work/cornell_mm.vdb" --levels 1 \
    --length-scale 1000 -q
expect 0 "Blender, a millimetre file" blender -b --factory-startup --python "$script" -- "$work/cornell_mm.vdb" \
    --render "$work/blender_mm.png" --resolution 96
python3 -c "import json,sys; r=json.loads(sys.argv[1]); print('render:', r); sys.exit(0 if r['lit_fraction'] > 0.5 and r['left_rgb'][0] > 1.5 * r['left_rgb'][1] else 1)" \
    "$(grep '^sharcbake_vdb_render: ' "$work/out.txt" | sed 's/^sharcbake_vdb_render: //')" &&
    echo "ok: a millimetre export renders lit" || fail "the millimetre export renders black or wrong"
# Exported Z-up (export-vdb --up z) and read as such: upright again, without the script's turn.
expect 0 "export Z-up" "$sharcbake" export-vdb "$work/cornell.sharc" -o "$work/cornell_z.vdb" --levels 1 --up z -q
expect 0 "Blender, a Z-up file" blender -b --factory-startup --python "$script" -- "$work/cornell_z.vdb" \
    --render "$work/blender_zz.png" --resolution 96 --up z
python3 -c "import json,sys; r=json.loads(sys.argv[1]); sys.exit(0 if r['white_from_top'] < 0.4 and r['left_rgb'][0] > 1.5 * r['left_rgb'][1] else 1)" \
    "$(grep '^sharcbake_vdb_render: ' "$work/out.txt" | sed 's/^sharcbake_vdb_render: //')" &&
    echo "ok: a file exported Z-up renders upright" || fail "the Z-up export does not render upright"
# The same file read as if it had been exported Z-up is not turned upright: the check can fail.
expect 0 "Blender, wrong up axis" blender -b --factory-startup --python "$script" -- "$work/cornell.vdb" \
    --render "$work/blender_z.png" --resolution 96 --up z
python3 -c "import json,sys; r=json.loads(sys.argv[1]); sys.exit(0 if r['white_from_top'] > 0.4 else 1)" \
    "$(grep '^sharcbake_vdb_render: ' "$work/out.txt" | sed 's/^sharcbake_vdb_render: //')" &&
    echo "ok: without the turn the lamp is not at the top (the upright check can fail)" ||
    fail "the upright check does not tell the orientations apart"

finish "Blender import"
