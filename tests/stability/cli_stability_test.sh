#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Degenerate input through the command line: a clear message and the documented exit code for an
# empty scene, a sky-only scene, a NaN vertex, a closed scene with no light and capacities out of
# range; the Stability section and the stability object of --stats-json for a table far too
# small and for a healthy bake; the stiff-scene warning (light making ~100 bounces) in a bake and a
# render of the rho = 0.99 furnace.
# Usage: cli_stability_test.sh SHARCBAKE SCENES_DIR WORK_DIR
set -u
sharcbake=$1
scenes=$2
work=$3
. "$(dirname "$0")/../cli_support.sh"

# Small glTF files: no meshes at all; one triangle with a NaN vertex; lines only; one triangle of no
# area; a closed tetrahedron with no emission, no lights and no sky.
python3 - "$work" <<'PY'
import base64, json, struct, sys
work = sys.argv[1]
def write(name, positions, indices, mode=4):
    doc = {"asset": {"version": "2.0"}, "scenes": [{"nodes": []}], "scene": 0}
    if positions:
        data = struct.pack("<%df" % len(positions), *positions)
        offset = len(data)
        data += struct.pack("<%dH" % len(indices), *indices)
        finite = [p for p in positions if p == p and abs(p) != float("inf")]
        doc["buffers"] = [{"byteLength": len(data),
                           "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}]
        doc["bufferViews"] = [{"buffer": 0, "byteOffset": 0, "byteLength": offset},
                              {"buffer": 0, "byteOffset": offset, "byteLength": len(indices) * 2}]
        doc["accessors"] = [{"bufferView": 0, "componentType": 5126, "count": len(positions) // 3, "type": "VEC3",
                             "min": [min(finite)] * 3, "max": [max(finite)] * 3},
                            {"bufferView": 1, "componentType": 5123, "count": len(indices), "type": "SCALAR"}]
        doc["materials"] = [{"doubleSided": True}]
        doc["meshes"] = [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0, "mode": mode}]}]
        doc["nodes"] = [{"mesh": 0}]
        doc["scenes"] = [{"nodes": [0]}]
    open(work + "/" + name, "w").write(json.dumps(doc))
write("empty.gltf", [], [])
write("nan_vertex.gltf", [0, 0, 0, 1, 0, 0, 0, float("nan"), 0], [0, 1, 2])
write("lines.gltf", [0, 0, 0, 1, 0, 0, 1, 1, 0], [0, 1, 1, 2], mode=1)  # a CAD export's edges
write("flat.gltf", [0, 0, 0, 1, 1, 1, 2, 2, 2], [0, 1, 2])  # one triangle of no area
write("dark.gltf", [0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 2], [0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3])
PY

expect 3 "empty scene" "$sharcbake" bake "$work/empty.gltf" -o "$work/a.sharc"
says "$work/err.txt" "no triangles to bake" "empty scene: clear message"
expect 3 "sky-only scene" "$sharcbake" bake "$work/empty.gltf" -o "$work/a.sharc" --sky 1,1,1
says "$work/err.txt" "no triangles to bake" "sky-only scene: clear message"
expect 3 "lines only" "$sharcbake" bake "$work/lines.gltf" -o "$work/a.sharc"
says "$work/err.txt" "no triangles to bake (1 primitive of points or lines skipped: they have no surface)" \
    "lines only: says the lines were skipped"
expect 3 "a triangle of no area" "$sharcbake" bake "$work/flat.gltf" -o "$work/a.sharc"
says "$work/err.txt" "no triangles to bake (1 degenerate triangle dropped: they have no area)" \
    "a triangle of no area: says it was dropped"
expect 3 "NaN vertex" "$sharcbake" bake "$work/nan_vertex.gltf" -o "$work/a.sharc"
says "$work/err.txt" "vertex 2 is NaN or infinite" "NaN vertex: names the vertex"
expect 1 "capacity 0" "$sharcbake" bake "$scenes/cornell_box/cornell_box.gltf" -o "$work/a.sharc" --capacity 0
expect 1 "capacity below one bucket" "$sharcbake" bake "$scenes/cornell_box/cornell_box.gltf" -o "$work/a.sharc" --capacity 15

# A closed scene without light: baked, black, and said so.
expect 0 "closed scene with no light" "$sharcbake" bake "$work/dark.gltf" -o "$work/dark.sharc" --iterations 4 \
    --resolution 32x32 --stats-json "$work/dark.json"
says "$work/err.txt" "the cache will be black" "dark scene: warned"
says "$work/err.txt" "give it one with --sky r,g,b" "dark scene: the warning names the fix"
says "$work/dark.json" '"non_finite_dropped": 0' "dark scene: no NaN/Inf"
# Its black render as a --reference has no scale for the image measures' epsilons: said, as
# compare says it.
expect 0 "black reference render" "$sharcbake" render "$work/dark.gltf" -o "$work/dark.exr" --resolution 16 --spp 1
expect 0 "bake against a black reference" "$sharcbake" bake "$work/dark.gltf" -o "$work/dark_ref.sharc" --iterations 2 \
    --resolution 32x32 --report "$work/dark_report" --reference "$work/dark.exr"
says "$work/err.txt" "warning: --reference .*dark.exr has no positive finite mean" "black reference: warned"

# A table far too small, and not a power of two: every failed insert counted, the lost energy stated.
expect 0 "bake with 1000 slots" "$sharcbake" bake "$scenes/cornell_box/cornell_box.gltf" -o "$work/small.sharc" \
    --iterations 8 --resolution 96x96 --capacity 1000 --stats-json "$work/small.json"
says "$work/out.txt" "^Stability:" "summary has a Stability section"
says "$work/out.txt" "warning: .* deposits found their hash bucket full .* raise --capacity" "table pressure: warning line"
says "$work/out.txt" "not a power of two" "capacity not a power of two: noted"
says "$work/small.json" '"failed_insert_energy_share": 0\.[0-9]' "stats JSON: lost energy share"
python3 -c "import json,sys; s=json.load(open(sys.argv[1]))['stability']; assert s['failed_inserts'] > 0 and s['capacity'] == 1000 and s['warnings'], s" \
    "$work/small.json" && echo "ok: stats JSON parses, failed inserts counted, warnings listed" ||
    { echo "FAIL: stats JSON"; failures=$((failures + 1)); }

# A healthy bake: the section says so.
expect 0 "healthy bake" "$sharcbake" bake "$scenes/cornell_box/cornell_box.gltf" -o "$work/ok.sharc" \
    --iterations 4 --resolution 64x64
says "$work/out.txt" "no problems found" "healthy bake: no warnings"

says "$work/out.txt" "light transport: the surfaces send 5[0-9]\.[0-9]*% of the light" "healthy bake: reflectance stated"

# A stiff scene: light makes about 1 / (1 - 0.99) = 100 bounces in the closed rho = 0.99 furnace.
# Both the bake and a render say so, with the count, instead of "no problems found" and a slow
# render without a word.
expect 0 "stiff bake" "$sharcbake" bake "$scenes/furnace_rho099/furnace_rho099.gltf" -o "$work/stiff.sharc" \
    --iterations 4 --resolution 64x64 --stats-json "$work/stiff.json"
says "$work/out.txt" "warning: light stays in this scene for about 10[0-9] bounces .* converges slowly" "stiff bake: warned"
python3 -c "import json,sys; s=json.load(open(sys.argv[1]))['stability']; assert 0.985 < s['scene_reflectance'] < 0.995, s" \
    "$work/stiff.json" && echo "ok: stats JSON holds the scene reflectance" ||
    { echo "FAIL: stats JSON scene_reflectance"; failures=$((failures + 1)); }
# -q leaves out the summary, not its warnings.
expect 0 "stiff bake, quiet" "$sharcbake" bake "$scenes/furnace_rho099/furnace_rho099.gltf" -o "$work/stiff_q.sharc" \
    --iterations 4 --resolution 64x64 -q
says "$work/err.txt" "warning: light stays in this scene for about 10[0-9] bounces" "stiff bake, quiet: warned on stderr"
if [ -s "$work/out.txt" ]; then fail "stiff bake, quiet: stdout not empty"; cat "$work/out.txt"; else echo "ok: stiff bake, quiet: stdout empty"; fi
expect 0 "stiff render" "$sharcbake" render "$scenes/furnace_rho099/furnace_rho099.gltf" -o "$work/stiff.exr" \
    --resolution 8 --spp 1
says "$work/err.txt" "warning: light stays in this scene for about 10[0-9] bounces .* the render is slow" "stiff render: warned"

finish "stability (command line)"
