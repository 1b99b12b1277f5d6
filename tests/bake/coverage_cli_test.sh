#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# A default bake serves every view: SHaRC's exact lookups from cameras at 0.25x to 8x the glTF
# camera's distance all hit; the same scene in millimetres or kilometres gets the same grid (in its
# units), the same voxel count and hit rate, and no warning; a level bias that does not fit the
# units is warned about; the automatic camera sees a lone floor, which has nothing to look up, and
# frames a closed double-sided box under the sky from outside (a black image is warned about), as
# the bake's camera sees it from around; a room beside a 10 km ground plane is served from its
# own camera; the room moved 2 km from the origin keeps its grid (keys decode near an anchor); a
# camera in a cupboard that free space's voxels leave without lookups keeps the grid to the cameras.
# Usage: coverage_cli_test.sh SHARCBAKE SCENES_DIR WORK_DIR
set -u
sharcbake=$1
scenes=$2
work=$3
. "$(dirname "$0")/../cli_support.sh"

cornell="$scenes/cornell_box/cornell_box.gltf"

# The Cornell box (a room with two blocks) with default settings.
expect 0 "default bake" "$sharcbake" bake "$cornell" -o "$work/cornell.sharc" --stats-json "$work/cornell.json"
says "$work/out.txt" "Views: free space" "the bake names the view region"
says "$work/out.txt" "predicted hit rate: " "the bake prints its predicted hit rate"
# Its one warning is the light 1 mm below the ceiling, which shares its voxels (docs/baking.md).
says "$work/err.txt" "warning: emissive material 'light': [0-9]*% of its area shares voxels" "the light leak is warned about"
# Captured as a pipeline's log (2>&1), the warning stays below the Scene line it follows: piped,
# stdout was buffered whole until exit, so every warning landed above the summary.
"$sharcbake" bake "$cornell" -o "$work/cornell_log.sharc" --iterations 2 > "$work/log.txt" 2>&1 ||
    fail "the bake with its output in one log failed"
awk '/^Scene /{scene=NR} /^warning: emissive material/{warning=NR} END{exit !(scene && warning > scene)}' \
    "$work/log.txt" || fail "in one log, the light's warning is not below the Scene line: $(head -3 "$work/log.txt")"
grep -v "warning: emissive material 'light'" "$work/err.txt" > "$work/other_warnings.txt"
[ -s "$work/other_warnings.txt" ] && fail "the default bake warned: $(cat "$work/other_warnings.txt")"
expect 0 "info" "$sharcbake" info "$work/cornell.sharc"
says "$work/out.txt" "levels_covered: 1-" "info shows the levels the file covers"
says "$work/out.txt" "view_region: free space" "info shows the region"
# Engines copy the grid values from info bit for bit: the text must give back the file's binary32
# values (a fitted level bias of 2.515625 was printed as 2.51562).
cp "$work/out.txt" "$work/info.txt"
expect 0 "info --json" "$sharcbake" info "$work/cornell.sharc" --json
python3 - "$work/info.txt" "$work/out.txt" <<'PY' || failures=$((failures + 1))
import json, re, struct, sys
text = open(sys.argv[1]).read()
grid = json.load(open(sys.argv[2]))["grid"]
f32 = lambda x: struct.unpack("<f", struct.pack("<f", float(x)))[0]
ok = True
for name, key in (("log base", "logarithm_base"), ("scene scale", "scene_scale"), ("level bias", "level_bias")):
    printed = re.search(name + r" ([-+0-9.e]+)", text).group(1)
    same = f32(printed) == f32(grid[key])
    ok = ok and same
    print(("ok" if same else "FAIL") + ": info prints %s %s, the file holds %r" % (name, printed, grid[key]))
sys.exit(0 if ok else 1)
PY

# The glTF camera is 2 units from the box's centre, looking at it: cameras from 0.5 to 16 units
# away on the same line ask for levels 1 to 6. SHaRC's exact lookup must hit 99% of the time.
for factor in 0.25 0.5 1 2 4 8; do
    z=$(awk "BEGIN { print 2 * $factor }")
    expect 0 "render from ${factor}x the camera's distance" "$sharcbake" render "$cornell" -o "$work/view.exr" \
        --look-at "0,0.5,$z,0,0.5,0" --fov 40 --resolution 64 --spp 4 --cache "$work/cornell.sharc" --no-png -q \
        --stats-json "$work/view.json"
    python3 - "$work/view.json" "$factor" <<'PY' || failures=$((failures + 1))
import json, sys
s = json.load(open(sys.argv[1]))
lookups = s["cache_hits"] + s["cache_misses"]
ok = lookups >= 50 and s["cache_hits"] >= 0.99 * lookups
print(("ok" if ok else "FAIL") + ": %sx: %d of %d lookups hit" % (sys.argv[2], s["cache_hits"], lookups))
sys.exit(0 if ok else 1)
PY
done

# The Cornell box under a new root node with the given TRS properties, in $work/NAME/.
rooted() {  # rooted NAME NODE_JSON
    mkdir -p "$work/$1"
    cp "$scenes/cornell_box/cornell_box.bin" "$work/$1/"
    python3 - "$cornell" "$2" "$work/$1/cornell_box.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
root = json.loads(sys.argv[2])
root["children"] = g["scenes"][0]["nodes"]
g["nodes"].append(root)
g["scenes"][0]["nodes"] = [len(g["nodes"]) - 1]
json.dump(g, open(sys.argv[3], "w"))
PY
}
# The same room in millimetres (x1000) and in kilometres (x0.001): a root node scales it.
rooted mm '{"name": "units", "scale": [1000, 1000, 1000]}'
rooted km '{"name": "units", "scale": [0.001, 0.001, 0.001]}'
small="--iterations 64 --resolution 640x360"
for units in unit mm km; do
    scene="$work/$units/cornell_box.gltf"
    [ "$units" = unit ] && scene="$cornell"
    expect 0 "bake in $units" "$sharcbake" bake "$scene" -o "$work/$units.sharc" $small --stats-json "$work/$units.json"
    # The light leak in any units: the check keys in the scene's own units, like the bake.
    says "$work/err.txt" "warning: emissive material 'light': [0-9]*% of its area shares voxels" "$units: the light leak is warned about"
    grep -v "warning: emissive material 'light'" "$work/err.txt" > "$work/other_warnings.txt"
    [ -s "$work/other_warnings.txt" ] && fail "the $units bake warned: $(cat "$work/other_warnings.txt")"
done
python3 - "$work/unit.json" "$work/mm.json" "$work/km.json" <<'PY' || failures=$((failures + 1))
import json, sys
unit, mm, km = (json.load(open(f)) for f in sys.argv[1:])
for name, s, k in (("mm", mm, 1000.0), ("km", km, 0.001)):
    voxels = s["live_voxels"] / unit["live_voxels"]
    size = s["grid"]["finest_voxel_size"] / (k * unit["grid"]["finest_voxel_size"])
    rate = s["predicted_hit_rate"]["rate"] - unit["predicted_hit_rate"]["rate"]
    ok = abs(voxels - 1) < 0.10 and abs(size - 1) < 0.02 and abs(rate) < 0.01
    print(("ok" if ok else "FAIL") + ": %s: voxels x%.4f, finest voxel x%.4f of the scaled unit's, hit rate %+.4f"
          % (name, voxels, size, rate))
    if not ok:
        sys.exit(1)
PY

# The same room 2 km from the origin: its level-1 cells lie near 300000, beyond the 17 bits a key
# keeps, so the keys decode near an anchor at the room's centre (info shows it) and the room keeps
# the grid it has at the origin (before the anchor: voxels 5x wider, 2000 / 58982 units), with no
# warning but the light leak (the tracer's guard of 256 float steps there, before the bound from
# the triangle's coordinates, was warned about as larger than the voxels).
rooted moved '{"name": "site", "translation": [2000.0, 0.0, 0.0]}'
expect 0 "bake moved 2 km" "$sharcbake" bake "$work/moved/cornell_box.gltf" -o "$work/moved.sharc" $small --stats-json "$work/moved.json"
grep -v "warning: emissive material 'light'" "$work/err.txt" > "$work/other_warnings.txt"
[ -s "$work/other_warnings.txt" ] && fail "the moved bake warned: $(cat "$work/other_warnings.txt")"
expect 0 "info --json moved" "$sharcbake" info "$work/moved.sharc" --json
python3 - "$work/unit.json" "$work/moved.json" "$work/out.txt" <<'PY' || failures=$((failures + 1))
import json, sys
unit, moved, info = (json.load(open(f)) for f in sys.argv[1:])
voxels = moved["live_voxels"] / unit["live_voxels"]
size = moved["grid"]["finest_voxel_size"] / unit["grid"]["finest_voxel_size"]
rate = moved["predicted_hit_rate"]["rate"] - unit["predicted_hit_rate"]["rate"]
anchor = info["grid"]["anchor"]
ok = abs(voxels - 1) < 0.10 and abs(size - 1) < 0.02 and abs(rate) < 0.01 and 1999 < anchor[0] < 2002
print(("ok" if ok else "FAIL") + ": moved 2 km: voxels x%.4f, finest voxel x%.4f of the unit's, hit rate %+.4f, anchor %s"
      % (voxels, size, rate, anchor))
sys.exit(0 if ok else 1)
PY

# Point lights fall off with the squared distance in the scene's units: the mm room's lamp is
# 10^6 times dimmer, and render says why; the same lamp in metres says nothing.
lamp() {  # lamp SCENE_GLTF OUT_GLTF HEIGHT
    python3 - "$1" "$2" "$3" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
g.setdefault("extensionsUsed", []).append("KHR_lights_punctual")
g.setdefault("extensions", {})["KHR_lights_punctual"] = {"lights": [{"type": "point", "intensity": 100.0}]}
g["nodes"].append({"name": "lamp", "translation": [0.0, float(sys.argv[3]), 0.0],
                   "extensions": {"KHR_lights_punctual": {"light": 0}}})
g["scenes"][0]["nodes"].append(len(g["nodes"]) - 1)
json.dump(g, open(sys.argv[2], "w"))
PY
}
mkdir -p "$work/unit"
cp "$scenes/cornell_box/cornell_box.bin" "$work/unit/"
lamp "$cornell" "$work/unit/lamp.gltf" 0.5
lamp "$work/mm/cornell_box.gltf" "$work/mm/lamp.gltf" 500
expect 0 "render the lamp in metres" "$sharcbake" render "$work/unit/lamp.gltf" -o "$work/lamp.exr" --resolution 8 --spp 1 -q
grep -q "point and spot lights" "$work/err.txt" && fail "the lamp in metres was called too far: $(cat "$work/err.txt")"
expect 0 "render the lamp in millimetres" "$sharcbake" render "$work/mm/lamp.gltf" -o "$work/lamp.exr" --resolution 8 --spp 1 -q
says "$work/err.txt" "warning: the scene's point and spot lights are a median .* units from the surfaces" \
    "a lamp in a millimetre scene is warned about"
says "$work/err.txt" "10^6 times too dim" "the warning says what millimetres do to it"

# A level bias given by hand that does not fit the units: a warning naming the fix.
expect 0 "the room shrunk to 1 mm with the SDK's level bias" "$sharcbake" bake "$work/km/cornell_box.gltf" -o "$work/x.sharc" \
    --iterations 2 --resolution 64x64 --level-bias 0
says "$work/err.txt" "warning: the scene's .* span only about" "too few voxels are warned about"
says "$work/err.txt" "level-bias auto" "the warning names the fix"
expect 0 "m scene with a far too large level bias" "$sharcbake" bake "$cornell" -o "$work/x.sharc" \
    --iterations 2 --resolution 64x64 --level-bias 12
says "$work/err.txt" "the voxel budget" "too many voxels are warned about"

expect 0 "a scene scale meant as a unit conversion" "$sharcbake" bake "$work/mm/cornell_box.gltf" -o "$work/x.sharc" \
    --iterations 2 --resolution 64x64 --scene-scale 0.05
says "$work/err.txt" "warning: --scene-scale 0.05 makes voxels" "a scene scale far from SHaRC's meaning is warned about"
says "$work/err.txt" "scene-scale auto" "the warning names the fix"

# Declared regions.
expect 0 "a region box" "$sharcbake" bake "$cornell" -o "$work/box.sharc" --iterations 8 --resolution 160x90 \
    --view-region box:-0.4,0.1,0.2,0.4,0.9,2.5
says "$work/out.txt" "Views: box" "a box region is described"
expect 0 "the glTF cameras as the region" "$sharcbake" bake "$cornell" -o "$work/gltf.sharc" --iterations 8 \
    --resolution 160x90 --view-region gltf
says "$work/out.txt" "Views: 1 camera position" "a glTF camera region is described"
expect 0 "a distance range" "$sharcbake" bake "$cornell" -o "$work/far.sharc" --iterations 8 --resolution 160x90 \
    --view-region distance:1.5
says "$work/out.txt" "ask for finer levels and miss" "the bake says which camera distances will miss"
expect 1 "a malformed region" "$sharcbake" bake "$cornell" -o "$work/x.sharc" --view-region box:1,2
says "$work/err.txt" "box:x0,y0,z0,x1,y1,z1" "the message names the accepted forms"
expect 1 "path region without a path" "$sharcbake" bake "$cornell" -o "$work/x.sharc" --view-region path
expect 1 "a non-number level bias" "$sharcbake" bake "$cornell" -o "$work/x.sharc" --level-bias fine
# Values each fine alone whose voxel has no float32 size (50 x 2^200 overflows: every voxel 0 wide)
# were baked into a cache of one cell per level; they are refused, naming the options and the fix.
expect 1 "a level bias whose voxels float32 cannot hold" "$sharcbake" bake "$cornell" -o "$work/refused.sharc" --level-bias 200
says "$work/err.txt" "--level-bias 200 give voxels float32 cannot represent" "the refusal names the options"
says "$work/err.txt" "Use --level-bias auto" "the refusal names the fix"
[ ! -e "$work/refused.sharc" ] || fail "a refused bake wrote a cache"
# Voxels 1e20 wide offset the wall-leak probe's rays beyond what Embree accepts (its assertion
# aborted the process, exit 134); the bake now runs, and warns that the voxels are too large.
expect 0 "voxels 1e20 wide" "$sharcbake" bake "$cornell" -o "$work/huge_voxels.sharc" --iterations 2 \
    --resolution 64x64 --scene-scale 1e-20
says "$work/err.txt" "the voxels are far larger than what the cameras see" "the bake warns about its voxels"

# A flat of rooms on a ground 2 km wide, with a window the roaming camera leaves by: free space
# gives the whole ground level 1, in voxels wider than the rooms, and the bake says so with the fix;
# the glTF cameras as the region count each part of the surface at their distance's level, and the
# budget the warning names makes the voxels fine enough. A bias given by hand gets a bias as its fix.
# By default (auto) the region is the glTF cameras: in free space SHaRC refuses their lookups. On a
# lawn 200 m wide free space refuses few, but its voxels are wider than the partitions: the same.
python3 "$(dirname "$0")/../bench/light_selection_scenes.py" "$work" || failures=$((failures + 1))
expect 0 "a flat on a 2 km ground by default" "$sharcbake" bake "$work/flat_on_ground.gltf" -o "$work/ground.sharc" \
    --iterations 2 --resolution 64x64
says "$work/out.txt" "Views: 4 camera positions (the glTF cameras, chosen by --view-region auto: in free space, level-1 voxels 5.58 wide would have SHaRC refuse 100% of their lookups (each bounce shorter than its voxel), here [0-9]*% in --voxel-budget 262144 (2 times the default)" \
    "by default the flat's grid is kept to its glTF cameras, in the least budget that makes their voxels fine enough"
grep -q "the voxels around" "$work/err.txt" && fail "the default region's choice is warned about: $(cat "$work/err.txt")"
expect 0 "a flat on a 200 m lawn by default" "$sharcbake" bake "$work/flat_on_lawn.gltf" -o "$work/lawn.sharc" \
    --iterations 2 --resolution 64x64 --stats-json "$work/lawn.json"
python3 -c 'import json, sys; sys.exit(json.load(open(sys.argv[1]))["camera"]["mode"] != "gltf_positions")' \
    "$work/lawn.json" || fail "the stats do not say the roaming camera stood at the glTF cameras' positions"
says "$work/out.txt" "Views: 4 camera positions (the glTF cameras, chosen by --view-region auto: in free space, camera 'room_2' would get voxels 0.556 wide, wider than 1/8 of the distance to what it sees (a median 1.14), which blur its view and leak light through walls thinner than one; here 0.0854 in --voxel-budget 196608 (1.5 times the default)" \
    "voxels wider than the partitions in free space keep the lawn's flat to its glTF cameras"
grep -q "the voxels around" "$work/err.txt" && fail "the lawn's default region is warned about: $(cat "$work/err.txt")"
says "$work/out.txt" "Camera: at the glTF cameras' positions, looking their own way and around" \
    "the roaming camera stays where the region's cameras are"
grep -q "never reached" "$work/err.txt" && fail "the lawn no camera of the region sees is called unreached: $(cat "$work/err.txt")"
expect 0 "the same on one thread" "$sharcbake" bake "$work/flat_on_lawn.gltf" -o "$work/lawn_1.sharc" \
    --iterations 2 --resolution 64x64 --threads 1
expect 0 "and on three" "$sharcbake" bake "$work/flat_on_lawn.gltf" -o "$work/lawn_3.sharc" \
    --iterations 2 --resolution 64x64 --threads 3
cmp -s "$work/lawn_1.sharc" "$work/lawn_3.sharc" || fail "baked from the cameras' positions, 1 and 3 threads differ"
expect 0 "the lawn's flat kept to the glTF cameras, exploring" "$sharcbake" bake "$work/flat_on_lawn.gltf" \
    -o "$work/lawn.sharc" --iterations 2 --resolution 64x64 --view-region gltf
says "$work/out.txt" "Camera: exploration" "a region given keeps the exploring camera"
expect 0 "the lawn's flat in free space" "$sharcbake" bake "$work/flat_on_lawn.gltf" -o "$work/lawn.sharc" \
    --iterations 2 --resolution 64x64 --view-region free
says "$work/err.txt" "warning: the voxels around camera 'room_2', 0.556 wide" "given free space, the same voxels are warned about"
# A hall 40 m wide with three cameras, and a fourth inside a cupboard 0.2 m wide: free space's
# 0.19 m voxels refuse nearly all of the cupboard's lookups and few of the hall's. Over all four
# cameras the share is far below 90%, yet one camera gets nothing (as 4 of VC.glb's 14 in
# glTF-Sample-Models did): the grid is kept to the glTF cameras, and the line names the camera.
python3 - "$work/hall.gltf" <<'PY'
import base64, json, struct, sys
def box(lo, hi, inward):
    corners = [(hi[0] if c & 1 else lo[0], hi[1] if c & 2 else lo[1], hi[2] if c & 4 else lo[2]) for c in range(8)]
    faces = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
    tris = [t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))]
    return corners, [(a, c, b) if inward else (a, b, c) for a, b, c in tris]
points, indices = [], []
for lo, hi, inward in (((-20, 0, -20), (20, 10, 20), True), ((5, 0, 5), (5.2, 0.2, 5.2), False)):
    c, t = box(lo, hi, inward)
    indices += [i + len(points) for tri in t for i in tri]
    points += c
data = b"".join(struct.pack("<3f", *p) for p in points) + struct.pack("<%dH" % len(indices), *indices)
cameras = [("hall_%d" % i, (x, 1.6, z)) for i, (x, z) in enumerate(((-10, 0), (0, 10), (10, -10)))]
cameras.append(("cupboard", (5.1, 0.1, 5.1)))
g = {"asset": {"version": "2.0"}, "scenes": [{"nodes": list(range(len(cameras) + 1))}],
     "nodes": [{"mesh": 0}] + [{"name": n, "camera": 0, "translation": list(p)} for n, p in cameras],
     "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.01}}],
     "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
     "materials": [{"pbrMetallicRoughness": {"metallicFactor": 0}, "baseColorFactor": [0.5, 0.5, 0.5, 1], "emissiveFactor": [0.2, 0.2, 0.2]}],
     "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
     "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 12 * len(points)},
                     {"buffer": 0, "byteOffset": 12 * len(points), "byteLength": 2 * len(indices)}],
     "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(points), "type": "VEC3",
                    "min": [min(p[k] for p in points) for k in range(3)], "max": [max(p[k] for p in points) for k in range(3)]},
                   {"bufferView": 1, "componentType": 5123, "count": len(indices), "type": "SCALAR"}]}
json.dump(g, open(sys.argv[1], "w"))
PY
expect 0 "a hall with a camera in a cupboard by default" "$sharcbake" bake "$work/hall.gltf" -o "$work/hall.sharc" \
    --iterations 2 --resolution 64x64
says "$work/out.txt" "Views: 4 camera positions (the glTF cameras, chosen by --view-region auto: in free space, level-1 voxels 0.192 wide would have SHaRC refuse 90% or more of the lookups of camera 'cupboard' (each bounce shorter than its voxel), here [0-9]*% of all in --voxel-budget" \
    "a camera free space leaves without lookups keeps the grid to the glTF cameras, and is named"
# With 24 cameras the summary lists the 15 lowest and one line for the rest (204 cameras printed
# 204 lines); the stats JSON keeps every one.
python3 - "$work/hall.gltf" "$work/hall_many.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
for i in range(20):
    g["nodes"].append({"name": "extra_%d" % i, "camera": 0, "translation": [-15 + 1.5 * i, 1.6, -5]})
    g["scenes"][0]["nodes"].append(len(g["nodes"]) - 1)
json.dump(g, open(sys.argv[2], "w"))
PY
expect 0 "a hall with 24 cameras" "$sharcbake" bake "$work/hall_many.gltf" -o "$work/hall_many.sharc" \
    --iterations 2 --resolution 64x64 --stats-json "$work/hall_many.json"
listed=$(grep -c "^    camera '" "$work/out.txt")
[ "$listed" -eq 15 ] || fail "24 cameras: $listed listed in the summary, expected the 15 lowest"
says "$work/out.txt" "^    and 9 more cameras" "the cameras not listed are counted in one line"
python3 -c 'import json, sys; v = json.load(open(sys.argv[1]))["predicted_hit_rate"]["views"]; sys.exit(sum(x.get("declared", False) for x in v) != 24)' \
    "$work/hall_many.json" || fail "the stats JSON does not list all 24 cameras"
# A budget other than the default is kept: in 200,000 voxels the cameras' grid gets 0.19 m voxels,
# wider than the voxel warning allows around cameras 1.14 m from their walls (0.76 m ones, the
# default budget's, rendered the flat 110% too bright), so free space it stays, warned about.
expect 0 "a flat on a 2 km ground in a budget given" "$sharcbake" bake "$work/flat_on_ground.gltf" -o "$work/ground.sharc" \
    --iterations 2 --resolution 64x64 --voxel-budget 200000
says "$work/out.txt" "Views: free space" "a budget given keeps the flat in free space"
expect 0 "a flat on a 2 km ground in free space" "$sharcbake" bake "$work/flat_on_ground.gltf" -o "$work/ground.sharc" \
    --iterations 2 --resolution 64x64 --view-region free
says "$work/err.txt" "warning: the voxels around camera 'room_[0-3]', 5.58 wide, are wider than 1/8 of the distance" \
    "voxels wider than the rooms around the cameras are warned about"
says "$work/err.txt" "view-region gltf --voxel-budget 524288 fits the voxels to their distances (0.0329 wide here" \
    "the warning names the fix"
expect 0 "the same with the glTF cameras as the region" "$sharcbake" bake "$work/flat_on_ground.gltf" \
    -o "$work/ground.sharc" --iterations 2 --resolution 64x64 --view-region gltf
says "$work/out.txt" "finest voxels 0.7611 wide, so .* at the levels the view region's cameras ask for" \
    "the fit counts the surface at the cameras' levels"
says "$work/err.txt" "0.761 wide, .* --voxel-budget 524288 makes them 0.0329 wide" "room-sized voxels are warned about"
expect 0 "and with the budget the warning names" "$sharcbake" bake "$work/flat_on_ground.gltf" \
    -o "$work/ground.sharc" --iterations 2 --resolution 64x64 --view-region gltf --voxel-budget 524288
grep -q "the voxels around" "$work/err.txt" && fail "the budget the warning names: the voxel warning stays"
expect 0 "the flat with a level bias giving room-sized voxels" "$sharcbake" bake "$work/flat.gltf" -o "$work/flat.sharc" \
    --iterations 2 --resolution 64x64 --level-bias -4.25
says "$work/err.txt" "because of --level-bias -4.25. --level-bias -1.82812 makes them 0.142 wide" \
    "a bias given by hand gets a bias as its fix"

# The SDK's rule (the bake camera's levels only) from far away: the render warns with the remedy,
# and the nearest-level fallback answers.
expect 0 "a bake without coverage" "$sharcbake" bake "$cornell" -o "$work/sdk.sharc" --iterations 16 \
    --resolution 320x180 --view-region bake-camera --camera-source gltf
expect 0 "render it from 8x the distance" "$sharcbake" render "$cornell" -o "$work/far.exr" \
    --look-at 0,0.5,16,0,0.5,0 --fov 20 --resolution 64 --spp 4 --cache "$work/sdk.sharc" --no-png
says "$work/err.txt" "warning: the cache answered only" "a low hit rate is warned about"
says "$work/err.txt" "view-region" "the warning names the remedy"
expect 0 "the same with the nearest-level fallback" "$sharcbake" render "$cornell" -o "$work/far.exr" \
    --look-at 0,0.5,16,0,0.5,0 --fov 20 --resolution 64 --spp 4 --cache "$work/sdk.sharc" --no-png \
    --cache-lookup nearest
says "$work/out.txt" "came from another level" "the fallback answers from another level"

# Two iterations of a 64x64 update image fill almost nothing: the warning names the lowest view and
# the scene's camera's own share beside it.
expect 0 "a short bake" "$sharcbake" bake "$cornell" -o "$work/short.sharc" --iterations 2 --resolution 64x64
says "$work/err.txt" "warning: the cache answers" "a short bake warns about its hit rate"
says "$work/err.txt" "; from camera 'camera' " "the hit-rate warning gives the scene's camera's share"
# One iteration: the camera itself is the lowest view, named once.
expect 0 "a one-iteration bake" "$sharcbake" bake "$cornell" -o "$work/one.sharc" --iterations 1 --resolution 64x64
says "$work/err.txt" "lowest: camera 'camera', " "the camera is the lowest view"
grep -q "; from camera 'camera'" "$work/err.txt" && fail "the warning names the camera twice: $(grep 'lowest:' "$work/err.txt")"

# A lone floor plane and no camera: the automatic camera sees it (not edge-on) and says where it is.
python3 - "$work/floor.gltf" <<'PY'
import base64, json, struct, sys
positions = [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)]
data = b"".join(struct.pack("<3f", *p) for p in positions) + struct.pack("<6H", 0, 2, 1, 0, 3, 2)
g = {"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
     "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
     "materials": [{"emissiveFactor": [1, 1, 1], "pbrMetallicRoughness": {"metallicFactor": 0}}],
     "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
     "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
     "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]},
                   {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}]}
json.dump(g, open(sys.argv[1], "w"))
PY
expect 0 "render a lone floor from the automatic camera" "$sharcbake" render "$work/floor.gltf" -o "$work/floor.exr" \
    --resolution 32 --spp 1 --no-png
says "$work/out.txt" "Camera: 'automatic' at (" "the automatic camera's pose is printed"
expect 0 "bake the floor" "$sharcbake" bake "$work/floor.gltf" -o "$work/floor.sharc" --iterations 2 --resolution 64x64
# Every first bounce off a lone floor leaves the scene: there is nothing for SHaRC to look up, and
# the bake says that instead of a rate of nothing ("100.0% of 0 lookups").
says "$work/out.txt" "predicted hit rate: no lookups from" "the bake says a lone floor has no lookups"
grep -q "of 0 lookups" "$work/out.txt" && fail "the bake rates 0 lookups: $(grep 'of 0 lookups' "$work/out.txt")"
expect 0 "the floor's primary hits" "$sharcbake" render "$work/floor.gltf" -o "$work/floor.exr" --resolution 32 \
    --spp 1 --no-png --cache "$work/floor.sharc" --debug-view cache
hits=$(sed -n "s/.* of \([0-9]*\) primary hits.*/\1/p" "$work/out.txt")
[ "${hits:-0}" -ge 100 ] || fail "the automatic camera sees the floor in ${hits:-0} of 1024 pixels (edge-on?)"
# Blender's default scene as Blender 3.4 exports it: a double-sided 2 m cube and its camera 10 m
# away, under a sky. A convex model's first bounces leave it; the one that grazes an edge was
# reported as "the cache answers 0.0% of SHaRC's lookups", with remedies. Too few lookups for a
# rate are said to be that.
cat > "$work/blender_cube.gltf" <<'GLTF'
{
 "asset": {"generator":"Khronos glTF Blender I/O v3.4.50","version":"2.0"},
 "scene": 0,
 "scenes": [{"name":"Scene","nodes":[0,1]}],
 "nodes": [{"mesh":0,"name":"Cube"},{"camera":0,"name":"Camera","rotation":[-0.20997299253940582,0.3857799470424652,0.09062844514846802,0.8937962055206299],"translation":[7.358891487121582,4.958309173583984,6.925790786743164]}],
 "cameras": [{"name":"Camera","perspective":{"aspectRatio":1.7777777777777777,"yfov":0.39959652046304894,"zfar":100,"znear":0.10000000149011612},"type":"perspective"}],
 "materials": [{"doubleSided":true,"name":"Material","pbrMetallicRoughness":{"baseColorFactor":[0.800000011920929,0.800000011920929,0.800000011920929,1],"metallicFactor":0,"roughnessFactor":0.5}}],
 "meshes": [{"name":"Cube","primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1,"NORMAL":2},"indices":3,"material":0}]}],
 "accessors": [{"bufferView":0,"componentType":5126,"count":24,"max":[1,1,1],"min":[-1,-1,-1],"type":"VEC3"},{"bufferView":1,"componentType":5126,"count":24,"type":"VEC2"},{"bufferView":2,"componentType":5126,"count":24,"type":"VEC3"},{"bufferView":3,"componentType":5123,"count":36,"type":"SCALAR"}],
 "bufferViews": [{"buffer":0,"byteLength":288,"byteOffset":0,"target":34962},{"buffer":0,"byteLength":192,"byteOffset":288,"target":34962},{"buffer":0,"byteLength":288,"byteOffset":480,"target":34962},{"buffer":0,"byteLength":72,"byteOffset":768,"target":34963}],
 "buffers": [{"byteLength":840,"uri":"data:application/octet-stream;base64,AACAPwAAgD8AAIC/AACAPwAAgD8AAIC/AACAPwAAgD8AAIC/AACAPwAAgL8AAIC/AACAPwAAgL8AAIC/AACAPwAAgL8AAIC/AACAPwAAgD8AAIA/AACAPwAAgD8AAIA/AACAPwAAgD8AAIA/AACAPwAAgL8AAIA/AACAPwAAgL8AAIA/AACAPwAAgL8AAIA/AACAvwAAgD8AAIC/AACAvwAAgD8AAIC/AACAvwAAgD8AAIC/AACAvwAAgL8AAIC/AACAvwAAgL8AAIC/AACAvwAAgL8AAIC/AACAvwAAgD8AAIA/AACAvwAAgD8AAIA/AACAvwAAgD8AAIA/AACAvwAAgL8AAIA/AACAvwAAgL8AAIA/AACAvwAAgL8AAIA/AAAgPwAAAD8AACA/AAAAPwAAID8AAAA/AADAPgAAAD8AAMA+AAAAPwAAwD4AAAA/AAAgPwAAgD4AACA/AACAPgAAID8AAIA+AADAPgAAgD4AAMA+AACAPgAAwD4AAIA+AAAgPwAAQD8AACA/AABAPwAAYD8AAAA/AAAAPgAAAD8AAMA+AABAPwAAwD4AAEA/AAAgPwAAAAAAACA/AACAPwAAYD8AAIA+AAAAPgAAgD4AAMA+AAAAAAAAwD4AAIA/AAAAAAAAAAAAAIC/AAAAAAAAgD8AAACAAACAPwAAAAAAAACAAAAAAAAAgL8AAACAAAAAAAAAAAAAAIC/AACAPwAAAAAAAACAAAAAAAAAAAAAAIA/AAAAAAAAgD8AAACAAACAPwAAAAAAAACAAAAAAAAAgL8AAACAAAAAAAAAAAAAAIA/AACAPwAAAAAAAACAAACAvwAAAAAAAACAAAAAAAAAAAAAAIC/AAAAAAAAgD8AAACAAAAAAAAAgL8AAACAAACAvwAAAAAAAACAAAAAAAAAAAAAAIC/AAAAAAAAAAAAAIA/AACAvwAAAAAAAACAAAAAAAAAgD8AAACAAAAAAAAAgL8AAACAAAAAAAAAAAAAAIA/AACAvwAAAAAAAACAAQAOABQAAQAUAAcACgAGABIACgASABYAFwATAAwAFwAMABAADwADAAkADwAJABUABQACAAgABQAIAAsAEQANAAAAEQAAAAQA"}]
}
GLTF
expect 0 "bake Blender's default cube" "$sharcbake" bake "$work/blender_cube.gltf" -o "$work/cube.sharc" \
    --iterations 64 --sky 1,1,1
# Its camera stands outside the cube's bounds, so the cube is also seen from around: exploring
# the bounds and the corner the camera faces left 96% of it without a finest voxel at 64
# iterations (75% at 512), and a runtime camera on the other side asked for voxels never made.
says "$work/out.txt" "views from around the scene (its cameras all stand outside its bounds" \
    "a model whose camera looks at it from outside is seen from around"
grep -q "was never reached" "$work/err.txt" && fail "the cube's far side is never reached: $(cat "$work/err.txt")"
says "$work/out.txt" "predicted hit rate: \(no lookups\|.* of only [0-9]* lookups\?\) from" \
    "the bake says a lone cube has (next to) nothing to look up"
grep -q "the cache answers" "$work/err.txt" && fail "a rate of a handful of lookups is warned about: $(cat "$work/err.txt")"
# A closed double-sided box and no camera (Blender's default material), under the sky: the centre
# of its bounds is closed all round, as in a room, but nothing lights the inside. The automatic
# camera stood there and the image was black, with no word said; it frames the box from outside.
python3 - "$work/box.gltf" <<'PY'
import base64, json, struct, sys
lo, hi = (-1.0, 0.0, -0.6), (1.0, 1.6, 0.6)
corners = [(hi[0] if c & 1 else lo[0], hi[1] if c & 2 else lo[1], hi[2] if c & 4 else lo[2]) for c in range(8)]
faces = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
indices = [i for a, b, c, d in faces for i in (a, b, c, a, c, d)]
data = b"".join(struct.pack("<3f", *p) for p in corners) + struct.pack("<36H", *indices)
g = {"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
     "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
     "materials": [{"doubleSided": True, "pbrMetallicRoughness": {"metallicFactor": 0}}],
     "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
     "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96}, {"buffer": 0, "byteOffset": 96, "byteLength": 72}],
     "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": list(lo), "max": list(hi)},
                   {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}]}
json.dump(g, open(sys.argv[1], "w"))
PY
expect 0 "render a closed double-sided box under the sky" "$sharcbake" render "$work/box.gltf" -o "$work/box.exr" \
    --resolution 32 --spp 1 --no-png --sky 1,1,1
says "$work/out.txt" "Camera: 'automatic' at (" "the automatic camera's pose is printed"
eye=$(sed -n "s/^Camera: 'automatic' at (\([^)]*\)).*/\1/p" "$work/out.txt")
echo "$eye" | awk -F', ' '{ exit ($1 > -1 && $1 < 1 && $2 > 0 && $2 < 1.6 && $3 > -0.6 && $3 < 0.6) }' ||
    fail "the automatic camera stands inside the box, at ($eye)"
grep -q "every pixel of the image is black" "$work/err.txt" && fail "the box renders black: $(cat "$work/err.txt")"
# From inside the box the image is black, and render says so and why.
expect 0 "render from inside the box" "$sharcbake" render "$work/box.gltf" -o "$work/box.exr" --resolution 32 \
    --spp 1 --no-png --sky 1,1,1 --look-at 0,0.8,0,0,0.8,-1
says "$work/err.txt" "warning: every pixel of the image is black: no light reaches what camera '--look-at' at (0, 0.8, 0)" \
    "a black image from inside a closed object is warned about"
says "$work/err.txt" "no ray from them leaves the scene, so the sky lights only its outside" \
    "the black image's warning says the sky does not get in"
# Baked, its inside (two thirds of the sides) is never reached, and the warning's remedies leave out
# --camera-source gltf: the scene has no camera (2CylinderEngine.glb without its camera was told so).
expect 0 "bake the closed box" "$sharcbake" bake "$work/box.gltf" -o "$work/box.sharc" --iterations 8 --sky 1,1,1
says "$work/err.txt" "of the surface area was never reached by the roaming camera" "the box's unreached inside is warned about"
grep -q "camera-source gltf" "$work/err.txt" && fail "a scene without cameras is told to bake from them: $(cat "$work/err.txt")"
# The box as a sky dome modelled as a plain mesh, around a camera, under a sun: the sun never gets
# in, and the bake said "no problems found" of a cache of zeros. The probe before the bake says the
# cache will be black, and names the dome's material as what blocks the sun.
python3 - "$work/box.gltf" "$work/dome.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
g["materials"][0]["name"] = "dome"
g["extensionsUsed"] = ["KHR_lights_punctual"]
g["extensions"] = {"KHR_lights_punctual": {"lights": [{"name": "Sun", "type": "directional", "intensity": 3}]}}
g["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}]
g["nodes"] += [{"camera": 0, "translation": [0, 0.8, 0]},
               {"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": [-0.7071068, 0, 0, 0.7071068]}]
g["scenes"][0]["nodes"] += [1, 2]
json.dump(g, open(sys.argv[2], "w"))
PY
expect 0 "bake a camera and a sun inside a closed dome" "$sharcbake" bake "$work/dome.gltf" -o "$work/dome.sharc" \
    --iterations 4
says "$work/err.txt" "warning: none of 4096 paths from the roaming camera met light (4096 of them met a surface), so the cache will be black" \
    "a sun inside a closed dome is warned about before the bake"
says "$work/err.txt" "directional light 'Sun': every ray towards it from the [0-9]* of them facing it is blocked, 100% first by material 'dome'" \
    "the warning names the dome's material as what keeps the sun out"
says "$work/out.txt" "energy: [0-9]* deposits, 0 deposited" "the cache the warning foretold is black"
# Baked without a camera, the box is seen from around: its inside, where the roaming camera
# stood before, is black and no runtime camera sees it, and 387 of the automatic camera's 401
# primary hits found no voxel.
expect 0 "bake the closed box under the sky" "$sharcbake" bake "$work/box.gltf" -o "$work/box.sharc" --iterations 64 \
    --sky 1,1,1
says "$work/out.txt" "Camera: 64 views from around the scene (it has no camera, and the free space inside its bounds is closed" \
    "a closed model under the sky without a camera is baked from around"
grep -q "^warning" "$work/err.txt" && fail "the box's bake warns: $(cat "$work/err.txt")"
# A convex white box (albedo 1) under a uniform sky of 1 sends back radiance 1 from every outside
# point: the voxels' mean is 1 (it was 5e-7 with the path inside the box, where no light is).
expect 0 "info --json of the box" "$sharcbake" info "$work/box.sharc" --json
python3 - "$work/out.txt" <<'PY' || failures=$((failures + 1))
import json, sys
mean = json.load(open(sys.argv[1]))["radiance"]["mean"]
if any(abs(c - 1.0) > 0.02 for c in mean):
    print("FAIL: the box's voxels hold a mean radiance of %s, not 1 (a white box under a sky of 1)" % mean)
    sys.exit(1)
print("ok: the box's voxels hold the furnace radiance 1 (mean %.4f)" % mean[0])
PY
# The same box as a modelling tool tessellates it, 64 x 64 quads a side sharing their vertices.
# Rays slipped through the shared edges into the box, where no light is, and some of its voxels
# held radiance 0; tracing is watertight now and the darkest voxel holds about half the sky.
python3 - "$work/box64.gltf" <<'PY'
import base64, json, struct, sys
n, lo, hi = 64, (-1.0, 0.0, -0.6), (1.0, 1.6, 0.6)
positions, indices = [], []
for axis in range(3):
    u, v = (axis + 1) % 3, (axis + 2) % 3
    for side in (lo, hi):
        base = len(positions)
        for j in range(n + 1):
            for i in range(n + 1):
                p = [0.0, 0.0, 0.0]
                p[axis], p[u], p[v] = side[axis], lo[u] + (hi[u] - lo[u]) * i / n, lo[v] + (hi[v] - lo[v]) * j / n
                positions.append(p)
        for j in range(n):
            for i in range(n):
                a = base + j * (n + 1) + i
                indices += [a, a + 1, a + n + 2, a, a + n + 2, a + n + 1]
data = b"".join(struct.pack("<3f", *p) for p in positions) + struct.pack("<%dI" % len(indices), *indices)
g = {"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
     "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
     "materials": [{"doubleSided": True, "pbrMetallicRoughness": {"metallicFactor": 0}}],
     "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
     "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 12 * len(positions)},
                     {"buffer": 0, "byteOffset": 12 * len(positions), "byteLength": 4 * len(indices)}],
     "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(positions), "type": "VEC3", "min": list(lo), "max": list(hi)},
                   {"bufferView": 1, "componentType": 5125, "count": len(indices), "type": "SCALAR"}]}
json.dump(g, open(sys.argv[1], "w"))
PY
expect 0 "bake the tessellated box under the sky" "$sharcbake" bake "$work/box64.gltf" -o "$work/box64.sharc" \
    --iterations 64 --sky 1,1,1
expect 0 "info --json of the tessellated box" "$sharcbake" info "$work/box64.sharc" --json
python3 - "$work/out.txt" <<'PY' || failures=$((failures + 1))
import json, sys
radiance = json.load(open(sys.argv[1]))["radiance"]
if min(radiance["min"]) < 0.25 or any(abs(c - 1.0) > 0.01 for c in radiance["mean"]):
    print("FAIL: the tessellated box's voxels hold radiance from %s (mean %s): rays leak through shared edges"
          % (radiance["min"], radiance["mean"]))
    sys.exit(1)
print("ok: no voxel of the tessellated box is dark (darkest %.3f, mean %.4f)" % (radiance["min"][0], radiance["mean"][0]))
PY
expect 0 "the box's primary hits through its cache" "$sharcbake" render "$work/box.gltf" -o "$work/box.exr" \
    --resolution 32 --spp 1 --no-png --sky 1,1,1 --cache "$work/box.sharc" --debug-view cache
says "$work/out.txt" "debug view 'cache': 0 of [0-9]* primary hits have no cached voxel" \
    "every primary hit of the automatic camera on the box has a voxel"
# The Cornell box with 70 cameras along its front and one inside the tall block by mistake: the
# winding puts that one inside a solid and is ignored, and the Camera line names it ("a glTF
# camera" before). Exploration's 64 points start at the first cameras, so the stray one's view is
# never baked: the hit-rate warning says why, beside its remedies (more iterations would not help).
cp "$scenes/cornell_box/cornell_box.bin" "$work/"
python3 - "$cornell" "$work/cornell_stray.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
nodes = g["scenes"][g.get("scene", 0)]["nodes"]
for k in range(70):
    g["nodes"].append({"name": "front%d" % k, "camera": 0,
                       "translation": [-0.4 + 0.8 * (k % 10) / 9, 0.2 + 0.6 * (k // 10) / 6, 0.45]})
    nodes.append(len(g["nodes"]) - 1)
g["nodes"].append({"name": "stray", "camera": 0, "translation": [-0.17, 0.3, -0.15]})
nodes.append(len(g["nodes"]) - 1)
json.dump(g, open(sys.argv[2], "w"))
PY
expect 0 "a camera inside a block" "$sharcbake" bake "$work/cornell_stray.gltf" -o "$work/stray.sharc" --iterations 32
says "$work/out.txt" "faces' winding ignored: it puts camera 'stray' (glTF camera 'camera') inside a solid" \
    "the Camera line names the camera inside a solid"
says "$work/err.txt" "The faces' winding puts camera 'stray' (glTF camera 'camera') inside a solid" \
    "the hit-rate warning says why the stray camera is not served"
# A closed 4 m room with its camera beside a 10 km ground plane under a sky (a building on its
# site). Fitted to the whole surface, the grid had 28 m voxels: SHaRC's tests refused every lookup
# from the room's camera, and the bake said "no first bounce hits a surface". The grid now fits
# what the cameras' free space sees, and the camera is served.
python3 - "$work/site.gltf" <<'PY'
import base64, json, struct, sys
def box_inward(lo, hi):
    c = [(x, y, z) for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
    faces = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
    return c, [i for f in faces for i in (f[0], f[2], f[1], f[0], f[3], f[2])]
room, room_idx = box_inward((-2, 0, -2.5), (2, 3, 2.5))
h = 5000.0
ground = [(-h, -0.01, -h), (-h, -0.01, h), (h, -0.01, h), (h, -0.01, -h)]
light = [(-0.5, 2.95, -0.5), (0.5, 2.95, -0.5), (0.5, 2.95, 0.5), (-0.5, 2.95, 0.5)]  # facing down
positions = room + ground + light
indices = room_idx + [8, 9, 10, 8, 10, 11] + [12, 13, 14, 12, 14, 15]
pos = b"".join(struct.pack("<3f", *p) for p in positions)
idx = struct.pack("<%dH" % len(indices), *indices)
data = pos + idx
lo = [min(p[k] for p in positions) for k in range(3)]
hi = [max(p[k] for p in positions) for k in range(3)]
g = {"asset": {"version": "2.0"}, "scenes": [{"nodes": [0, 1]}],
     "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 1.5, 2.0]}],
     "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.01}}],
     "meshes": [{"primitives": [
         {"attributes": {"POSITION": 0}, "indices": 1, "material": 0},
         {"attributes": {"POSITION": 0}, "indices": 2, "material": 0},
         {"attributes": {"POSITION": 0}, "indices": 3, "material": 1}]}],
     "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0}},
                   {"emissiveFactor": [1, 1, 1], "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}}],
     "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
     "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
                     {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx)}],
     "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(positions), "type": "VEC3", "min": lo, "max": hi},
                   {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR", "byteOffset": 0},
                   {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR", "byteOffset": 72},
                   {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR", "byteOffset": 84}],
     "extras": {"sharcbake": {"sky_radiance": [0.3, 0.4, 0.6]}}}
json.dump(g, open(sys.argv[1], "w"))
PY
expect 0 "bake a room beside a 10 km ground plane" "$sharcbake" bake "$work/site.gltf" -o "$work/site.sharc" \
    --iterations 16 --resolution 320x180 --stats-json "$work/site.json"
says "$work/out.txt" "the rest is out of its sight" "the grid is fitted to what the room's camera sees"
python3 - "$work/site.json" <<'PY' || failures=$((failures + 1))
import json, sys
p = json.load(open(sys.argv[1]))["predicted_hit_rate"]
camera = [v for v in p["views"] if v["declared"]][0]
ok = camera["lookups"] >= 1000 and camera["rate"] >= 0.9
print(("ok" if ok else "FAIL") + ": the room's camera: %d lookups, rate %s, %d refused" % (camera["lookups"], camera["rate"], camera["refused"]))
sys.exit(0 if ok else 1)
PY
expect 0 "render the room through its cache" "$sharcbake" render "$work/site.gltf" -o "$work/site.exr" \
    --resolution 64 --spp 4 --cache "$work/site.sharc" --no-png --stats-json "$work/site_render.json"
python3 - "$work/site_render.json" <<'PY' || failures=$((failures + 1))
import json, sys
s = json.load(open(sys.argv[1]))
lookups = s["cache_hits"] + s["cache_misses"]
ok = lookups >= 1000 and s["cache_hits"] >= 0.9 * lookups
print(("ok" if ok else "FAIL") + ": render through the site's cache: %d of %d lookups hit" % (s["cache_hits"], lookups))
sys.exit(0 if ok else 1)
PY
# The same bake with the SDK's level bias: 1 m voxels is still fine; 41 m (bias -10) refuses
# every lookup, and the bake and the render say why instead of "no first bounce hits a surface".
expect 0 "bake the site with 41 m voxels" "$sharcbake" bake "$work/site.gltf" -o "$work/coarse.sharc" \
    --iterations 2 --resolution 64x64 --level-bias -10
says "$work/out.txt" "all [0-9]* refused: each bounce is shorter than its voxel" "the prediction counts refused lookups"
says "$work/err.txt" "refuse every one of the" "the bake warns that every lookup is refused"
expect 0 "render through 41 m voxels" "$sharcbake" render "$work/site.gltf" -o "$work/coarse.exr" \
    --resolution 32 --spp 1 --cache "$work/coarse.sharc" --no-png
says "$work/err.txt" "refused all [0-9]* cache lookups from this camera" "render says every lookup was refused"
# The lone floor 1e6 units from the origin: the tracer's ray offset there (up to 1.7 units, 16
# float32 roundings of the coordinates) is most of the floor's size; render said nothing while its
# image came out wrong (with the guard of 256 float steps, 16 units).
python3 - "$work/floor.gltf" "$work/floor_far.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
g["nodes"][0]["translation"] = [1e6, 0, 0]
json.dump(g, open(sys.argv[2], "w"))
PY
expect 0 "render a floor 1e6 from the origin" "$sharcbake" render "$work/floor_far.gltf" -o "$work/far.exr" \
    --resolution 16 --spp 1 --no-png
says "$work/err.txt" "ray origins up to 1.[67][0-9]* off surfaces.*move the scene towards the origin" "render warns about the ray offset"
expect 0 "render the floor at the origin" "$sharcbake" render "$work/floor.gltf" -o "$work/near.exr" \
    --resolution 16 --spp 1 --no-png
grep -q "ray origins" "$work/err.txt" && fail "render warns about the ray offset at the origin: $(cat "$work/err.txt")"
# The Cornell box's camera turned to look away from it, baked along the glTF camera: no path hits
# a surface, and the file written holds no voxel. The bake says so plainly, not with a level 0.
mkdir -p "$work/away"
cp "$scenes/cornell_box/cornell_box.bin" "$work/away/"
python3 - "$cornell" "$work/away/cornell_box.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
for n in g["nodes"]:
    if "camera" in n:
        n["rotation"] = [0.0, 1.0, 0.0, 0.0]
json.dump(g, open(sys.argv[2], "w"))
PY
expect 0 "a camera that looks away from the scene" "$sharcbake" bake "$work/away/cornell_box.gltf" \
    -o "$work/away.sharc" --camera-source gltf --iterations 2 --resolution 64x64
says "$work/err.txt" "warning: the cache is empty: no path from the roaming camera hit a surface" \
    "an empty cache is warned about"
says "$work/err.txt" "or give --camera-source explore" "the empty cache's warning names the remedy"
says "$work/out.txt" "has no voxel (the cache is empty" "the coverage line of an empty cache"
grep -q "(level 0)" "$work/out.txt" && fail "an empty cache's coverage names level 0"
grep -q "was never reached" "$work/err.txt" && fail "an empty cache also gets the unreached-surface warning"
# A sky dome modelled as an unlit sphere of radius 30 around a ground and a box, no camera: the bake
# explores the lit inside, and render's automatic camera, which framed the dome from 150 units
# out (seeing its outer side, which has no voxel), frames the ground and the box from inside it.
python3 - "$work/dome.gltf" <<'PY'
import base64, json, math, struct, sys
R, nu, nv = 30.0, 32, 16
dome = [(R * math.sin(math.pi * j / nv) * math.cos(2 * math.pi * (i + 0.3) / nu), R * math.cos(math.pi * j / nv),
         R * math.sin(math.pi * j / nv) * math.sin(2 * math.pi * (i + 0.3) / nu)) for j in range(nv + 1) for i in range(nu + 1)]
dome_idx = [k for j in range(1, nv - 1) for i in range(nu) for k in
            (j * (nu + 1) + i, (j + 1) * (nu + 1) + i, j * (nu + 1) + i + 1,
             j * (nu + 1) + i + 1, (j + 1) * (nu + 1) + i, (j + 1) * (nu + 1) + i + 1)]
dome_idx += [k for i in range(nu) for k in (i, nu + 1 + i, nu + 2 + i)]  # the top cap
dome_idx += [k for i in range(nu) for k in ((nv - 1) * (nu + 1) + i, nv * (nu + 1) + i, (nv - 1) * (nu + 1) + i + 1)]
ground = [(-10, 0, -10), (10, 0, -10), (10, 0, 10), (-10, 0, 10)]
ground_idx = [0, 2, 1, 0, 3, 2]
lo, hi = (-1, 0, -1), (1, 2, 1)
box = [(hi[0] if c & 1 else lo[0], hi[1] if c & 2 else lo[1], hi[2] if c & 4 else lo[2]) for c in range(8)]
box_idx = [k for a, b, c, d in [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
           for k in (a, b, c, a, c, d)]
data, views, accessors, prims = b"", [], [], []
for material, (points, idx) in enumerate([(ground, ground_idx), (box, box_idx), (dome, dome_idx)]):
    for blob, kind in ((b"".join(struct.pack("<3f", *p) for p in points), "VEC3"), (struct.pack("<%dI" % len(idx), *idx), "SCALAR")):
        views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(blob)})
        data += blob
        accessor = {"bufferView": len(views) - 1, "componentType": 5126 if kind == "VEC3" else 5125,
                    "count": len(points) if kind == "VEC3" else len(idx), "type": kind}
        if kind == "VEC3":
            accessor.update(min=[min(p[k] for p in points) for k in range(3)], max=[max(p[k] for p in points) for k in range(3)])
        accessors.append(accessor)
    prims.append({"attributes": {"POSITION": len(accessors) - 2}, "indices": len(accessors) - 1, "material": material})
g = {"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_materials_unlit"],
     "scenes": [{"nodes": [0, 1, 2]}], "nodes": [{"mesh": i} for i in range(3)], "meshes": [{"primitives": [p]} for p in prims],
     "materials": [{"doubleSided": True, "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0}},
                   {"doubleSided": True, "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.3, 0.2, 1], "metallicFactor": 0}},
                   {"doubleSided": True, "extensions": {"KHR_materials_unlit": {}},
                    "pbrMetallicRoughness": {"baseColorFactor": [0.4, 0.6, 1.0, 1], "metallicFactor": 0}}],
     "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
     "bufferViews": views, "accessors": accessors}
json.dump(g, open(sys.argv[1], "w"))
PY
expect 0 "bake the scene in a sky dome" "$sharcbake" bake "$work/dome.gltf" -o "$work/dome.sharc" --iterations 64
says "$work/out.txt" "Camera: exploration" "the inside of the dome is explored"
expect 0 "render the dome's cache from the automatic camera" "$sharcbake" render "$work/dome.gltf" \
    -o "$work/dome.exr" --resolution 32 --spp 1 --no-png --cache "$work/dome.sharc" --debug-view cache
eye=$(sed -n "s/^Camera: 'automatic' at (\([^)]*\)).*/\1/p" "$work/out.txt")
echo "$eye" | awk -F', ' '{ exit !($1 * $1 + $2 * $2 + $3 * $3 < 30 * 30) }' ||
    fail "the automatic camera stands outside the dome, at ($eye)"
says "$work/out.txt" "debug view 'cache': 0 of [0-9]* primary hits have no cached voxel" \
    "every primary hit of the automatic camera inside the dome has a voxel"

finish "coverage"
