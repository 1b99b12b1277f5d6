#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Alpha cut-outs through the whole renderer, against an analytic answer. Under a uniform sky of
# radiance 1, a Lambert ground of albedo 0.5 lit through a large black cover of alpha 0.3
# (BLEND: opaque on 30% of its points) has radiance 0.5 x 0.7 = 0.35, the same as an uncovered
# ground of albedo 0.35: the camera sits under the cover, so renders of both must agree.
# The same holds through a cache baked from each scene.
# Usage: cutout_test.sh SHARCBAKE WORK_DIR
set -u
sharcbake=$1
work=$2
. "$(dirname "$0")/../cli_support.sh"

python3 - "$work" <<'PY'
import base64, json, struct, sys

def scene(path, ground_albedo, cover):
    # Ground: 400 m square at y = 0; cover: 400 m square at y = 1, both facing up and down.
    quads = [(0.0, [ground_albedo] * 3, None)]
    if cover:
        quads.append((1.0, [0.0, 0.0, 0.0], 0.3))
    data, accessors, views, meshes, materials = b"", [], [], [], []
    for y, color, alpha in quads:
        positions = struct.pack("<12f", -200, y, -200, 200, y, -200, 200, y, 200, -200, y, 200)
        indices = struct.pack("<6H", 0, 2, 1, 0, 3, 2) + b"\0\0"
        for blob, target, acc in ((positions, 34962, {"componentType": 5126, "count": 4, "type": "VEC3",
                                                      "min": [-200, y, -200], "max": [200, y, 200]}),
                                  (indices, 34963, {"componentType": 5123, "count": 6, "type": "SCALAR"})):
            views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(blob), "target": target})
            acc["bufferView"] = len(views) - 1
            accessors.append(acc)
            data += blob
        material = {"pbrMetallicRoughness": {"baseColorFactor": color + [alpha if alpha else 1.0],
                                             "metallicFactor": 0.0, "roughnessFactor": 1.0},
                    "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}, "doubleSided": True}
        if alpha:
            material["alphaMode"] = "BLEND"
        materials.append(material)
        meshes.append({"primitives": [{"attributes": {"POSITION": len(accessors) - 2},
                                       "indices": len(accessors) - 1, "material": len(materials) - 1}]})
    nodes = [{"mesh": i} for i in range(len(meshes))]
    # Under the cover, looking down at the ground.
    nodes.append({"camera": 0, "translation": [0, 0.6, 0], "rotation": [-0.5, 0, 0, 0.8660254]})
    gltf = {"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_materials_specular"],
            "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes, "meshes": meshes,
            "materials": materials, "accessors": accessors, "bufferViews": views,
            "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.01}}],
            "buffers": [{"byteLength": len(data),
                         "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}]}
    json.dump(gltf, open(path, "w"))

scene(sys.argv[1] + "/covered.gltf", 0.5, True)
scene(sys.argv[1] + "/open.gltf", 0.35, False)
PY

render="--sky 1,1,1 --resolution 48 -q --no-png"
expect 0 "render under the cover" "$sharcbake" render "$work/covered.gltf" -o "$work/covered.exr" $render --spp 256
says "$work/err.txt" "stochastic cut-out" "BLEND is warned about as a stochastic cut-out"
expect 0 "render the open ground" "$sharcbake" render "$work/open.gltf" -o "$work/open.exr" $render --spp 256 --seed 1
expect 0 "compare" "$sharcbake" compare "$work/covered.exr" "$work/open.exr" --json
python3 - "$work/out.txt" <<'PY' || fail "covered and open renders differ"
import json, sys
m = json.load(open(sys.argv[1]))
ok = abs(m["relative_bias"]) < 0.02
print(("ok" if ok else "FAIL") + ": ground under a 30% cover vs an open ground of 0.7x the albedo:", m)
sys.exit(0 if ok else 1)
PY

bake="--sky 1,1,1 --iterations 48 --resolution 320x180 --capacity 262144 -q"
expect 0 "bake under the cover" "$sharcbake" bake "$work/covered.gltf" -o "$work/covered.sharc" $bake
expect 0 "bake the open ground" "$sharcbake" bake "$work/open.gltf" -o "$work/open.sharc" $bake
expect 0 "render through the covered cache" "$sharcbake" render "$work/covered.gltf" --cache "$work/covered.sharc" \
    -o "$work/covered_cached.exr" $render --spp 64
expect 0 "render through the open cache" "$sharcbake" render "$work/open.gltf" --cache "$work/open.sharc" \
    -o "$work/open_cached.exr" $render --spp 64
expect 0 "compare cached" "$sharcbake" compare "$work/covered_cached.exr" "$work/open_cached.exr" --json
python3 - "$work/out.txt" <<'PY' || fail "covered and open cached renders differ"
import json, sys
m = json.load(open(sys.argv[1]))
ok = abs(m["relative_bias"]) < 0.03
print(("ok" if ok else "FAIL") + ": the same through caches:", m)
sys.exit(0 if ok else 1)
PY

finish "alpha cut-outs"
