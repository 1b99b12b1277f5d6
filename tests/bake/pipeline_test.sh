#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# What a build pipeline relies on: progress lines in logs, warnings that --quiet does not hide
# (the loader's, dropped non-finite samples), skies scaled beyond float32 refused, provenance in
# the JSON outputs, and renders that refuse a cache of another scene or sky.
# Usage: pipeline_test.sh SHARCBAKE SCENES_DIR WORK_DIR
set -u
sharcbake=$1
scenes=$2
work=$3
. "$(dirname "$0")/../cli_support.sh"

cornell="$scenes/cornell_box/cornell_box.gltf"
small="--resolution 320x180 --capacity 65536"

# Progress: stdout is a file here, so a bake prints periodic lines and one closing line.
expect 0 "bake into a log" "$sharcbake" bake "$cornell" -o "$work/c.sharc" --iterations 48 $small --progress-interval 0.05 \
    --stats-json "$work/bake.json" --checkpoint "$work/c.ckpt"
says "$work/out.txt" "^progress: Baking [0-9]*/48 iterations ([0-9]*%), [0-9.]*s elapsed, ETA [0-9.m-]*s*, [0-9]* voxels" \
    "periodic progress lines with elapsed time, ETA and voxels"
says "$work/out.txt" "^progress: Baking 48/48 iterations (100%) in " "a closing progress line"
expect 0 "bake, progress lines off" "$sharcbake" bake "$cornell" -o "$work/c0.sharc" --iterations 8 $small --progress-interval 0
grep -q "^progress:" "$work/out.txt" && fail "--progress-interval 0 still printed progress lines"
expect 0 "bake -q" "$sharcbake" bake "$cornell" -o "$work/cq.sharc" --iterations 8 $small -q --progress-interval 0.01
[ -s "$work/out.txt" ] && fail "bake -q printed to stdout: $(head -c 200 "$work/out.txt")"

# --quiet hides progress and summaries, never warnings: a mesh without a material is warned about.
cp "$scenes/cornell_box/cornell_box.bin" "$work/"
python3 - "$cornell" "$work/edited.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
for mesh in g["meshes"]:
    for primitive in mesh["primitives"]:
        primitive.pop("material", None)
        break
    break
json.dump(g, open(sys.argv[2], "w"))
PY
expect 0 "render -q of a scene with a loader warning" "$sharcbake" render "$work/edited.gltf" -o "$work/e.exr" \
    --resolution 8 --spp 1 -q
says "$work/err.txt" "^warning: .*no material" "-q still prints the loader's warnings"

# Radiance beyond float32: a furnace whose walls emit 3e38 sums past 3.4e38 on every path. The
# samples are dropped (exit 0, as before), with a warning that -q does not hide either.
furnace="$scenes/furnace_rho050/furnace_rho050.gltf"
cp "$scenes/furnace_rho050/furnace_rho050.bin" "$work/"
python3 - "$furnace" "$work/overflow.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
g.setdefault("extensionsUsed", []).append("KHR_materials_emissive_strength")
g["materials"][0].setdefault("extensions", {})["KHR_materials_emissive_strength"] = {"emissiveStrength": 3e38}
json.dump(g, open(sys.argv[2], "w"))
PY
expect 0 "render -q of a scene whose radiance overflows" "$sharcbake" render "$work/overflow.gltf" -o "$work/o.exr" \
    --resolution 8 --spp 2 -q --no-png
says "$work/err.txt" "^warning: 128 of 128 path samples (100%) were NaN or infinite and were dropped" \
    "-q still warns about dropped non-finite samples, with their count and share"
says "$work/err.txt" "overflowed float32.*--sky-scale is too large. Scale the scene's light down" \
    "the warning says what they mean and what to do"
expect 0 "render of a scene whose radiance overflows" "$sharcbake" render "$work/overflow.gltf" -o "$work/o.exr" \
    --resolution 8 --spp 2 --no-png
says "$work/err.txt" "^warning: 128 of 128 path samples" "without -q the warning is on stderr too"
says "$work/out.txt" "dropped 128 non-finite path samples" "and the summary still counts them"
expect 0 "render of the furnace as it is" "$sharcbake" render "$furnace" -o "$work/o.exr" --resolution 8 --spp 2 --no-png -q
grep -q "non-finite\|NaN" "$work/err.txt" && fail "a furnace of finite radiance warned about non-finite samples"

# --sky-scale is checked against the map it scales: a product beyond float32 is refused as a
# texel stored infinite is (the furnace's render, radiance about 2, as the map).
expect 0 "render a sky map" "$sharcbake" render "$furnace" -o "$work/sky.exr" --resolution 8x4 --spp 4 --no-png -q
expect 0 "a sky map at --sky-scale 1e30" "$sharcbake" render "$cornell" -o "$work/s.exr" --sky-exr "$work/sky.exr" \
    --sky-scale 1e30 --resolution 8 --spp 1 --no-png -q
expect 3 "a sky map at --sky-scale 3e38" "$sharcbake" render "$cornell" -o "$work/s.exr" --sky-exr "$work/sky.exr" \
    --sky-scale 3e38 --resolution 8 --spp 1 --no-png -q
says "$work/err.txt" "sky.exr: 96 colour values are infinite at --sky-scale 3e+38" "the refusal names the map, the count and the scale"
expect 3 "a sky map whose total overflows at --sky-scale 5e37" "$sharcbake" bake "$cornell" -o "$work/s.sharc" \
    --sky-exr "$work/sky.exr" --sky-scale 5e37 --iterations 1 -q
says "$work/err.txt" "sky.exr: the sky's total radiance (over all directions) is infinite at --sky-scale 5e+37" \
    "a sky of finite texels whose total overflows is refused as well"

# Provenance in the bake's stats JSON.
python3 - "$work/bake.json" "$work/c.sharc" "$work/c.ckpt" <<'PY' || fail "bake stats JSON provenance"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["schema"] == "sharcbake.bake-stats/1", j["schema"]
assert j["tool"]["name"] == "sharcbake" and j["tool"]["version"], j["tool"]
assert j["scene"]["path"].endswith("cornell_box.gltf") and j["scene"]["content_hash"].startswith("fnv1a64:"), j["scene"]
assert j["scene"]["warnings"] == [], j["scene"]
assert j["output"] == sys.argv[2] and j["checkpoint"] == sys.argv[3]
assert j["camera"]["mode"] == "explore" and "exploration" in j["camera"]["description"], j["camera"]
s = j["settings"]
assert s["scene_hash"] == j["scene"]["content_hash"] and s["iterations"] == 48 and s["capacity"] == 65536, s
assert s["seed"] == 0 and s["resolution"] == "320x180" and isinstance(s["level_bias"], float), s
print("ok: bake stats JSON carries schema, tool, scene, outputs, camera mode and settings")
PY

# --stats-json - writes the JSON to stdout, alone: what is printed for people (the scene, the plan,
# progress lines, the summary) goes to stderr, and no file named "-" is made (the cwd is $work).
(cd "$work" && "$sharcbake" bake "$cornell" -o "$work/s.sharc" --iterations 8 $small --progress-interval 0.01 \
    --stats-json - 2>"$work/err.txt") | python3 -c '
import json, sys
j = json.load(sys.stdin)
assert j["schema"] == "sharcbake.bake-stats/1" and j["iterations"] == 8, j["schema"]
' && echo "ok: bake --stats-json - prints the JSON alone on stdout" || fail "bake --stats-json -: stdout is not the JSON alone"
says "$work/err.txt" "^Scene .*cornell_box.gltf" "with --stats-json -, the scene line goes to stderr"
says "$work/err.txt" "^progress: Baking 8/8 iterations" "with --stats-json -, progress lines go to stderr"
says "$work/err.txt" "^Baked 8 iterations" "with --stats-json -, the summary goes to stderr"
(cd "$work" && "$sharcbake" render "$cornell" -o "$work/s.exr" --resolution 8 --spp 1 --stats-json - \
    2>"$work/err.txt") | python3 -c '
import json, sys
j = json.load(sys.stdin)
assert j["schema"] == "sharcbake.render-stats/1" and j["width"] == 8, j["schema"]
' && echo "ok: render --stats-json - prints the JSON alone on stdout" || fail "render --stats-json -: stdout is not the JSON alone"
says "$work/err.txt" "^Wrote .*s.exr" "with --stats-json -, the render's summary goes to stderr"
[ ! -e "$work/-" ] || fail "--stats-json - wrote a file named -"
expect 1 "--stats-json - with several scenes" "$sharcbake" bake "$cornell" "$scenes/two_rooms/two_rooms.gltf" \
    -o "$work/several" --stats-json - $small
says "$work/err.txt" "one JSON document per scene" "the refusal says why"
# Binary outputs take no "-": refused before any work, and no file named "-" is made.
(cd "$work" && "$sharcbake" bake "$cornell" -o - $small >"$work/out.txt" 2>"$work/err.txt")
[ $? -eq 1 ] && echo "ok: bake -o - refused (exit 1)" || fail "bake -o -: not refused with exit 1"
says "$work/err.txt" "the cache cannot go to standard output" "bake -o -: the refusal says why"
(cd "$work" && "$sharcbake" render "$cornell" -o - --resolution 8 --spp 1 >"$work/out.txt" 2>"$work/err.txt")
[ $? -eq 1 ] && echo "ok: render -o - refused (exit 1)" || fail "render -o -: not refused with exit 1"
[ ! -e "$work/-" ] || fail "-o - wrote a file named -"

# info --json gives metadata numbers as numbers.
expect 0 "info --json" "$sharcbake" info "$work/c.sharc" --json
python3 - "$work/out.txt" <<'PY' || fail "info --json metadata types"
import json, sys
m = json.load(open(sys.argv[1]))["metadata"]
assert m["iterations"] == 48 and m["seed"] == 0 and m["capacity"] == 65536, m
assert isinstance(m["scene_scale"], float) and isinstance(m["resolution"], str) and isinstance(m["scene_hash"], str), m
print("ok: info --json metadata numbers are numbers")
PY

# A render refuses a cache baked from another scene (here an edited copy) or under another sky.
expect 3 "render with another scene's cache" "$sharcbake" render "$work/edited.gltf" --cache "$work/c.sharc" \
    -o "$work/x.exr" --resolution 8 --spp 1 -q
says "$work/err.txt" "another scene or another version" "the refusal says why"
says "$work/err.txt" "allow-cache-mismatch" "the refusal names the override"
[ ! -e "$work/x.exr" ] || fail "a refused render wrote its image"
expect 3 "render with a cache of another sky" "$sharcbake" render "$cornell" --cache "$work/c.sharc" --sky 1,1,1 \
    -o "$work/x.exr" --resolution 8 --spp 1 -q
says "$work/err.txt" "another sky" "the sky refusal says why"
expect 0 "render with another scene's cache, allowed" "$sharcbake" render "$work/edited.gltf" --cache "$work/c.sharc" \
    --allow-cache-mismatch -o "$work/x.exr" --resolution 8 --spp 1 -q --stats-json "$work/render.json"
says "$work/err.txt" "^warning: .*another scene" "the override still warns"
# Through another scene's cache few lookups hit; the warning says why, not to bake other views.
expect 0 "render another scene through the cache, allowed" "$sharcbake" render "$scenes/two_rooms/two_rooms.gltf" \
    --cache "$work/c.sharc" --allow-cache-mismatch -o "$work/x.exr" --resolution 32 --spp 2 -q
says "$work/err.txt" "it was baked for another scene or sky" "the low hit rate is put down to the mismatch"
grep -q "view-region" "$work/err.txt" && fail "the mismatched cache's warning advises another view region"

# The render's stats JSON: provenance and the camera's pose.
python3 - "$work/render.json" "$work/c.sharc" <<'PY' || fail "render stats JSON provenance"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["schema"] == "sharcbake.render-stats/1" and j["cache"] == sys.argv[2], j
assert j["scene"]["path"].endswith("edited.gltf") and any("no material" in w for w in j["scene"]["warnings"]), j["scene"]
c = j["camera"]
assert len(c["position"]) == 3 and len(c["forward"]) == 3 and len(c["up"]) == 3 and c["yfov"] > 0, c
print("ok: render stats JSON carries schema, scene, cache and the camera pose")
PY

finish "pipeline"
