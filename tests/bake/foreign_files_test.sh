#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Files from other tools: Blender's camera names (node = object, camera = camera data) and
# cameras without names through render --camera and the bake's hit-rate lines; glTF versions
# other than 2.0; messages that name the real cause (a spot cone, a camera's aspect ratio, a
# buffer's data: URI); other 3D formats given for a glTF file.
# Usage: foreign_files_test.sh SHARCBAKE WORK_DIR
set -u
sharcbake=$1
work=$2
. "$(dirname "$0")/../cli_support.sh"

# scene.py OUT [camera-spec...] [--spot OUTER] [--dark] [--aspect A]: a lit floor under cameras.
# A camera spec is NODE_NAME/CAMERA_NAME ("-" for none); all look down at the floor.
cat > "$work/scene.py" <<'PY'
import base64, json, struct, sys
out, args = sys.argv[1], sys.argv[2:]
floor = [-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1]
data = struct.pack("<12f", *floor) + struct.pack("<6H", 0, 2, 1, 0, 3, 2)
doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
       "nodes": [{"mesh": 0}], "cameras": [],
       "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0},
                      "emissiveFactor": [1, 1, 1]}],
       "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
       "buffers": [{"byteLength": len(data),
                    "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
       "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                       {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
       "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                      "min": [-1, 0, -1], "max": [1, 0, 1]},
                     {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}]}
down = [-0.7071068, 0, 0, 0.7071068]  # -Z turned to -Y
i = 0
while i < len(args):
    a = args[i]
    if a == "--spot":  # the floor's emission off, a spot straight down instead
        doc["materials"][0]["emissiveFactor"] = [0, 0, 0]
        doc["extensionsUsed"] = ["KHR_lights_punctual"]
        doc["extensions"] = {"KHR_lights_punctual": {"lights": [
            {"name": "Needle", "type": "spot", "intensity": 1000,
             "spot": {"innerConeAngle": 0, "outerConeAngle": float(args[i + 1])}}]}}
        doc["nodes"].append({"translation": [0, 1, 0], "rotation": down,
                             "extensions": {"KHR_lights_punctual": {"light": 0}}})
        doc["scenes"][0]["nodes"].append(len(doc["nodes"]) - 1)
        i += 2
        continue
    if a == "--dark":  # the spot gives nothing
        doc["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = 0
        i += 1
        continue
    if a == "--aspect":
        doc["cameras"][-1]["perspective"]["aspectRatio"] = float(args[i + 1])
        i += 2
        continue
    node_name, camera_name = a.split("/")
    camera = {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}
    if camera_name != "-":
        camera["name"] = camera_name
    doc["cameras"].append(camera)
    node = {"camera": len(doc["cameras"]) - 1, "translation": [0.2 * len(doc["cameras"]), 1.5, 0], "rotation": down}
    if node_name != "-":
        node["name"] = node_name
    doc["nodes"].append(node)
    doc["scenes"][0]["nodes"].append(len(doc["nodes"]) - 1)
    i += 1
if not doc["cameras"]:
    del doc["cameras"]
json.dump(doc, open(out, "w"))
PY
scene() { python3 "$work/scene.py" "$@"; }
render() { "$sharcbake" render "$@" -o "$work/image.png" --resolution 16 --spp 1 -q; }

# --- Blender's names: --camera takes the node's (object's) name, the camera's name or an index.
scene "$work/bl_room.gltf" Persp/Camera Ortho/Camera.001
expect 0 "--camera by the node's name (Blender's object name)" render "$work/bl_room.gltf" --camera Persp
expect 0 "--camera by the glTF camera's name" render "$work/bl_room.gltf" --camera Camera.001
expect 0 "--camera by index #1" render "$work/bl_room.gltf" --camera '#1'
expect 0 "--camera by bare index 1" render "$work/bl_room.gltf" --camera 1
"$sharcbake" render "$work/bl_room.gltf" -o "$work/image.png" --resolution 16 --spp 1 --camera Persp > "$work/out.txt" 2>&1
says "$work/out.txt" "camera 'Persp' (glTF camera 'Camera')" "the render names its camera by node and camera name"
expect 1 "--camera with a name no camera has" render "$work/bl_room.gltf" --camera Side
says "$work/err.txt" "#0 node 'Persp', glTF camera 'Camera', #1 node 'Ortho', glTF camera 'Camera.001'" \
    "the error lists every camera by node name and camera name"
expect 1 "--camera #2 of two cameras" render "$work/bl_room.gltf" --camera '#2'

# A node name two cameras share is refused, both listed; node names win over camera names.
scene "$work/twins.gltf" Main/A Main/B B/C
expect 1 "--camera with a node name two cameras share" render "$work/twins.gltf" --camera Main
says "$work/err.txt" "2 cameras have that node name (#0 node 'Main', glTF camera 'A', #1 node 'Main', glTF camera 'B')" \
    "the ambiguous name's candidates are listed"
says "$work/err.txt" "'#0'" "the ambiguity error says how to choose by index"
"$sharcbake" render "$work/twins.gltf" -o "$work/image.png" --resolution 16 --spp 1 --camera B > "$work/out.txt" 2>&1
says "$work/out.txt" "camera 'B' (glTF camera 'C')" "a node's name is matched before a camera's"

# --- Cameras without any name: listed, chosen and reported by their index.
scene "$work/nameless.gltf" -/- -/-
expect 1 "--camera of a scene of nameless cameras" render "$work/nameless.gltf" --camera Main
says "$work/err.txt" "it has #0 (no names), #1 (no names)" "nameless cameras are listed distinguishably"
"$sharcbake" render "$work/nameless.gltf" -o "$work/image.png" --resolution 16 --spp 1 --camera '#1' > "$work/out.txt" 2>&1
says "$work/out.txt" "camera #1 in" "a nameless camera is named by its index"
expect 0 "bake a scene of nameless cameras" "$sharcbake" bake "$work/nameless.gltf" -o "$work/nameless.sharc" \
    --iterations 2 --resolution 32x32 --prediction-views 2
says "$work/out.txt" "    camera #0: " "the hit-rate lines name a nameless camera by its index"
says "$work/out.txt" "    camera #1: " "each nameless camera by its own index"
grep -q "camera ''" "$work/out.txt" "$work/err.txt" && fail "a camera is named by an empty name"

# --- glTF versions other than 2.x: refused as invalid input (exit 3), naming the version.
python3 - "$work/bl_room.gltf" "$work/v1.gltf" "$work/v3.gltf" <<'PY'
import json, sys
doc = json.load(open(sys.argv[1]))
for path, version in ((sys.argv[2], "1.0"), (sys.argv[3], "3.0")):
    doc["asset"]["version"] = version
    json.dump(doc, open(path, "w"))
PY
expect 3 "a glTF 1.0 file" "$sharcbake" bake "$work/v1.gltf" -o "$work/v1.sharc"
says "$work/err.txt" "glTF 1.0 files are not supported" "the error names glTF 1.0"
expect 3 "a glTF 3.0 file" "$sharcbake" render "$work/v3.gltf" -o "$work/v3.png"
says "$work/err.txt" "glTF 3.0 files are not supported (asset.version '3.0')" "the error names the version"

# --- A needle-thin spot lights its disc: the scene has a light, and the warning is not given.
scene "$work/needle.gltf" Top/Camera --spot 1e-6
expect 0 "render under a spot of 1e-6 rad" render "$work/needle.gltf"
grep -q "no lights" "$work/err.txt" && fail "a spot with a narrow cone is called no light: $(cat "$work/err.txt")"
# A light that gives nothing is named, with why.
scene "$work/dark.gltf" Top/Camera --spot 0.5 --dark
expect 0 "render under a spot of intensity 0" render "$work/dark.gltf"
says "$work/err.txt" "no light from its punctual lights (spot light 'Needle': intensity 0 or a black colour)" \
    "a light that gives no light is named"

# --- An absurd aspect ratio: ignored with a warning naming the camera; a large image blames it.
scene "$work/thin.gltf" Top/Camera --aspect 1e-6
expect 0 "render --resolution 64 of a camera with aspect ratio 1e-6" "$sharcbake" render "$work/thin.gltf" \
    -o "$work/thin.png" --resolution 64 --spp 1 -q
says "$work/err.txt" "camera 'Top' (glTF camera 'Camera'): aspectRatio 1e-06 is outside" "the absurd aspect ratio is warned about"
scene "$work/tall.gltf" Top/Camera --aspect 0.02
expect 1 "--resolution 20000 of a camera with aspect ratio 0.02" "$sharcbake" render "$work/tall.gltf" \
    -o "$work/tall.png" --resolution 20000 --spp 1 -q
says "$work/err.txt" "camera 'Top' (glTF camera 'Camera') has aspect ratio 0.02, which would make the image 20000 x 1000000" \
    "the error names the camera's aspect ratio as the cause"
says "$work/err.txt" "--resolution 20000x20000" "the error suggests giving both sides"

# --- A buffer whose byteLength disagrees with its data: URI: a short message with both sizes.
python3 - "$work/bl_room.gltf" "$work/long_uri.gltf" <<'PY'
import base64, json, sys
doc = json.load(open(sys.argv[1]))
data = bytes(range(256)) * 8
doc["buffers"].append({"byteLength": len(data) + 4,
                       "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()})
json.dump(doc, open(sys.argv[2], "w"))
PY
expect 3 "a data: URI shorter than its byteLength" "$sharcbake" render "$work/long_uri.gltf" -o "$work/long.png"
says "$work/err.txt" "buffer 1: data: URI data:application/octet-stream;base64,AAECAwQFBgcICQoLDA0ODxA... holds 2048 bytes, but the buffer's byteLength is 2052" \
    "the message names the buffer and both sizes"
[ "$(wc -c < "$work/err.txt")" -lt 400 ] || fail "the data: URI message is $(wc -c < "$work/err.txt") bytes long"

# --- A buffer file left behind (the .gltf copied without its .bin): a missing file, exit 2, named
# with the folder looked in, as a missing image is; and a GLB cut short says so (exit 3).
python3 - "$work/bl_room.gltf" "$work/moved/room.gltf" "$work/whole.glb" <<'PY'
import base64, json, os, struct, sys
doc = json.load(open(sys.argv[1]))
data = base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1])
doc["buffers"][0]["uri"] = "room.bin"
os.makedirs(os.path.dirname(sys.argv[2]), exist_ok=True)
json.dump(doc, open(sys.argv[2], "w"))
del doc["buffers"][0]["uri"]
text = json.dumps(doc).encode()
text += b" " * (-len(text) % 4)
data += b"\0" * (-len(data) % 4)
chunks = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(data), 0x004E4942) + data
open(sys.argv[3], "wb").write(struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks)
PY
expect 2 "bake a glTF whose .bin is missing" "$sharcbake" bake "$work/moved/room.gltf" -o "$work/moved.sharc"
says "$work/err.txt" "room.gltf: buffer 'room.bin' not found beside the scene (looked in $(cd "$work/moved" && pwd -P))" \
    "the missing buffer is named with the folder looked in"
expect 0 "render the whole GLB" render "$work/whole.glb"
head -c 200 "$work/whole.glb" > "$work/cut.glb"
expect 3 "render a GLB cut short" render "$work/cut.glb"
says "$work/err.txt" "cut.glb: the GLB header says the file is [0-9]* bytes, but it has 200: the file is cut short" \
    "the GLB cut short is called that, not \"Invalid glTF binary\""

# --- Other 3D formats: named, with how to convert them, as invalid input (exit 3).
printf 'mtllib room.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' > "$work/room.obj"
expect 3 "bake an OBJ file" "$sharcbake" bake "$work/room.obj" -o "$work/room.sharc"
says "$work/err.txt" "room.obj: an OBJ file, not glTF 2.0: convert it, e.g. \`assimp export $work/room.obj $work/room.glb -f glb2\` or Blender's glTF exporter" \
    "the OBJ file is named as one, with the command that converts it"
python3 -c "import struct, sys; sys.stdout.buffer.write(b' ' * 80 + struct.pack('<I', 40) + b'[' * 2000)" > "$work/part.stl"
expect 3 "render a binary STL file" "$sharcbake" render "$work/part.stl" -o "$work/part.png"
says "$work/err.txt" "part.stl: an STL file, not glTF 2.0" "the binary STL is named as one"
grep -q "JSON" "$work/err.txt" && fail "the binary STL gets the JSON parser's error: $(cat "$work/err.txt")"

finish foreign_files_test
