#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Hostile inputs and outputs (docs/untrusted_input.md): an output never
# replaces a device, a FIFO, one of the command's inputs or a file of another kind, a failed write keeps the previous
# file, and crafted scenes and caches end with the documented exit code, quickly.
# Usage: hardening_test.sh SHARCBAKE SCENES_DIR WORK_DIR
set -u
sharcbake=$1
scenes=$2
work=$3
. "$(dirname "$0")/../cli_support.sh"

furnace="$scenes/furnace_rho090/furnace_rho090.gltf"
quick="--iterations 2 --resolution 16x16 -q"
expect 0 "a small bake" "$sharcbake" bake "$furnace" -o "$work/a.sharc" $quick
cp "$work/a.sharc" "$work/a.orig"

# 1. Non-regular outputs are refused before any work; a symlinked output stays a link; the mode is kept.
expect 2 "bake -o /dev/null is refused" "$sharcbake" bake "$furnace" -o /dev/null $quick
says "$work/err.txt" "a device" "the message says the output is a device"
[ -c /dev/null ] || fail "/dev/null is no longer a character device"
# A folder that refuses new files although its permission bits (or root) allow them: sysfs. The
# bake used to run to its end and fail at the write; it is refused before any work now.
if [ -d /sys ] && ! touch /sys/sharcbake-probe 2>/dev/null; then
    expect 2 "bake into /sys is refused before baking" "$sharcbake" bake "$furnace" -o /sys/x.sharc --iterations 100000
    grep -q "^Baked" "$work/out.txt" && fail "the bake ran before its output was refused"
    says "$work/err.txt" "/sys" "the message names the folder"
fi
# An existing file of another kind is not replaced: arguments swapped (bake -o scene.gltf ...)
# destroyed the scene without a word. A file of the output's own kind, or an empty one, is replaced.
cp "$furnace" "$work/precious.gltf"
echo "notes" > "$work/notes.txt"
expect 1 "bake -o over a glTF scene" "$sharcbake" bake "$furnace" -o "$work/precious.gltf" $quick
says "$work/err.txt" "precious.gltf: exists and is not a sharcbake cache" "the refusal names the file and why"
cmp -s "$furnace" "$work/precious.gltf" || fail "bake -o replaced a glTF scene"
expect 1 "bake --checkpoint over a text file" "$sharcbake" bake "$furnace" -o "$work/b.sharc" --checkpoint "$work/notes.txt" $quick
expect 1 "merge -o over a glTF scene" "$sharcbake" merge "$work/a.sharc" -o "$work/precious.gltf"
expect 1 "export-vdb -o over a text file" "$sharcbake" export-vdb "$work/a.sharc" -o "$work/notes.txt" -q
cmp -s "$furnace" "$work/precious.gltf" && [ "$(cat "$work/notes.txt")" = "notes" ] || fail "an output replaced another kind of file"
cp "$work/a.sharc" "$work/replaced.sharc"
expect 0 "bake -o over a cache" "$sharcbake" bake "$furnace" -o "$work/replaced.sharc" $quick
: > "$work/empty.vdb"
expect 0 "export-vdb -o over an empty file" "$sharcbake" export-vdb "$work/a.sharc" -o "$work/empty.vdb" -q
expect 0 "export-vdb -o over a VDB" "$sharcbake" export-vdb "$work/a.sharc" -o "$work/empty.vdb" -q

expect 2 "export-vdb -o /dev/full is refused" "$sharcbake" export-vdb "$work/a.sharc" -o /dev/full
mkfifo "$work/fifo_out.exr"
expect 2 "render -o FIFO is refused" "$sharcbake" render "$furnace" -o "$work/fifo_out.exr" --resolution 8 --spp 1 -q
[ -p "$work/fifo_out.exr" ] || fail "the FIFO was replaced"
mkdir -p "$work/real"
ln -s real/linked.sharc "$work/link.sharc"
expect 0 "bake through a symlink" "$sharcbake" bake "$furnace" -o "$work/link.sharc" $quick
[ -L "$work/link.sharc" ] || fail "the symlinked output is no longer a link"
cmp -s "$work/real/linked.sharc" "$work/a.sharc" || fail "the link's target does not hold the cache"
chmod 600 "$work/real/linked.sharc"
expect 0 "bake over a mode-600 file" "$sharcbake" bake "$furnace" -o "$work/link.sharc" $quick
[ "$(stat -c %a "$work/real/linked.sharc")" = 600 ] || fail "the output's mode was not kept: $(stat -c %a "$work/real/linked.sharc")"

# 2. export-vdb: a failed write (file size limit, as on a full disk) exits 2 and keeps the old file.
expect 0 "export-vdb" "$sharcbake" export-vdb "$work/a.sharc" -o "$work/a.vdb" -q
cp "$work/a.vdb" "$work/a.vdb.orig"
expect 2 "export-vdb on a full disk" sh -c "trap '' XFSZ; ulimit -f 1; exec '$sharcbake' export-vdb '$work/a.sharc' -o '$work/a.vdb' --split-normals -q"
says "$work/err.txt" "previous file is untouched" "the message says the write failed and the old file is kept"
cmp -s "$work/a.vdb" "$work/a.vdb.orig" || fail "the failed export changed the previous VDB"
ls "$work" | grep -q "tmp-" && fail "a temporary file was left behind: $(ls "$work")"

# 3. An output that names an input is refused (exit 1) and the input is untouched.
mkdir -p "$work/tq" && cp "$scenes/textured_quad/"* "$work/tq/"
cp "$work/tq/textured_quad.gltf" "$work/tq.orig.gltf"
cp "$work/tq/textured_quad.png" "$work/tq.orig.png"
expect 1 "bake -o the scene" "$sharcbake" bake "$work/tq/textured_quad.gltf" -o "$work/tq/textured_quad.gltf" $quick
cmp -s "$work/tq/textured_quad.gltf" "$work/tq.orig.gltf" || fail "bake overwrote its scene"
expect 1 "render whose PNG preview is the scene's texture" "$sharcbake" render "$work/tq/textured_quad.gltf" \
    -o "$work/tq/textured_quad.exr" --resolution 8 --spp 1 -q
says "$work/err.txt" "PNG preview" "the message names the PNG preview"
cmp -s "$work/tq/textured_quad.png" "$work/tq.orig.png" || fail "render replaced the scene's texture"
expect 1 "render --cache C -o C" "$sharcbake" render "$furnace" --cache "$work/a.sharc" -o "$work/a.sharc" --no-png --resolution 8 --spp 1 -q
# The output's extension picks its format: .png is the preview alone, anything else but .exr is refused.
expect 0 "render -o X.png" "$sharcbake" render "$furnace" -o "$work/x.png" --resolution 8 --spp 1 -q
[ "$(head -c 4 "$work/x.png" | od -An -tx1 | tr -d ' ')" = "89504e47" ] || fail "render -o X.png did not write a PNG"
[ ! -e "$work/x.exr" ] || fail "render -o X.png also wrote an EXR"
expect 1 "render -o X.tiff" "$sharcbake" render "$furnace" -o "$work/x.tiff" --resolution 8 --spp 1 -q
says "$work/err.txt" "picks its format" "the message says how the name picks the format"
[ ! -e "$work/x.tiff" ] || fail "render -o X.tiff wrote a file"
expect 1 "export-vdb A -o A" "$sharcbake" export-vdb "$work/a.sharc" -o "$work/a.sharc"
ln -s a.sharc "$work/alias.sharc"
expect 1 "export-vdb A -o a link to A" "$sharcbake" export-vdb "$work/a.sharc" -o "$work/alias.sharc"
expect 1 "merge A -o A" "$sharcbake" merge "$work/a.sharc" -o "$work/a.sharc"
expect 1 "bake -o F --checkpoint F" "$sharcbake" bake "$furnace" -o "$work/f.bin" --checkpoint "$work/f.bin" $quick
expect 1 "bake --stats-json onto the cache" "$sharcbake" bake "$furnace" -o "$work/f.sharc" --stats-json "$work/f.sharc" $quick
cmp -s "$work/a.sharc" "$work/a.orig" || fail "a refused command changed the cache"

# 4. A failed --stats-json write exits 2 (the bytes go through the same checked write).
expect 2 "stats JSON into /dev/full" "$sharcbake" render "$furnace" -o "$work/s.exr" --no-png --resolution 8 --spp 1 -q --stats-json /dev/full
expect 0 "stats JSON written" "$sharcbake" render "$furnace" -o "$work/s.exr" --no-png --resolution 8 --spp 1 -q --stats-json "$work/s.json"
says "$work/s.json" '"width"' "the stats JSON has its content"

# 6. Floating-point options refuse NaN and infinities (range checks alone let NaN through).
expect 1 "render --fov nan" "$sharcbake" render "$furnace" -o "$work/n.exr" --look-at 0,0,3,0,0,0 --fov nan --resolution 8 --spp 1 -q
expect 1 "render --exposure inf" "$sharcbake" render "$furnace" -o "$work/n.exr" --exposure inf --resolution 8 --spp 1 -q
expect 1 "bake --time-budget nan" "$sharcbake" bake "$furnace" -o "$work/n.sharc" --time-budget nan $quick
# A budget spent before the first iteration: the empty cache was blamed on the camera ("check that
# the camera looks at the scene"), with advice to give more iterations.
expect 0 "bake --time-budget 1e-9" "$sharcbake" bake "$furnace" -o "$work/n.sharc" --time-budget 1e-9 $quick
says "$work/err.txt" "no iteration ran (stopped by --time-budget before the first)" "the empty cache is explained"
grep -q "camera" "$work/err.txt" && fail "a bake that ran no iteration blames the camera"
# A table far too small: its gaps were blamed on the roaming camera, next to the warning naming
# --capacity; that one alone is said now.
expect 0 "bake --capacity 16" "$sharcbake" bake "$furnace" -o "$work/n.sharc" --capacity 16 $quick
says "$work/err.txt" "found their hash bucket full" "the full table is named"
grep -q "roaming camera" "$work/err.txt" && fail "a full table's gaps are blamed on the roaming camera"
expect 1 "bake --sky-scale nan" "$sharcbake" bake "$furnace" -o "$work/n.sharc" --sky-scale nan $quick
expect 1 "bake --sky with a negative radiance" "$sharcbake" bake "$furnace" -o "$work/n.sharc" --sky=-1,0,0 $quick
# Cameras beyond +-1e9 (where no vertex may lie): rays from 1e20 failed Embree's ray.valid()
# assertion (SIGABRT), and eye and target 2e19 apart were called "the same point".
expect 1 "render --look-at 1e20 out" "$sharcbake" render "$furnace" -o "$work/n.exr" --look-at 1e20,0,0,0,0,0 --resolution 8 --spp 1 -q
says "$work/err.txt" "--look-at: a coordinate beyond +-1e9, where nothing of a scene may lie" "the far --look-at is named"
printf '# a waypoint far out\n0 0 3 0 0 0\n1e19 0 0 -1e19 0 0 60\n' >"$work/far_path.txt"
expect 3 "bake --camera-path with a waypoint 1e19 out" "$sharcbake" bake "$furnace" -o "$work/n.sharc" --camera-path "$work/far_path.txt" $quick
says "$work/err.txt" "far_path.txt:3: a coordinate beyond +-1e9, where nothing of a scene may lie" "the far waypoint is named"

# 7. A CRC-valid checkpoint claiming 0xFFFFFFFF iterations is refused at once (rule C8).
expect 0 "bake with a checkpoint" "$sharcbake" bake "$furnace" -o "$work/c.sharc" --checkpoint "$work/c.ckpt" $quick
python3 - "$work/c.ckpt" "$work/huge.ckpt" <<'PY' || fail "could not craft the checkpoint"
import struct, sys, zlib
d = bytearray(open(sys.argv[1], 'rb').read())
count = struct.unpack_from('<I', d, 28)[0]
for i in range(count):
    e = 64 + 32 * i
    if d[e:e + 4] == b'STAT':
        offset, length = struct.unpack_from('<QQ', d, e + 8)
        struct.pack_into('<I', d, offset, 0xFFFFFFFF)                     # iterations_done
        struct.pack_into('<I', d, e + 24, zlib.crc32(d[offset:offset + length]))
struct.pack_into('<I', d, 60, zlib.crc32(d[64:64 + 32 * count], zlib.crc32(d[:60])))
open(sys.argv[2], 'wb').write(d)
PY
expect 3 "resume from a checkpoint with 0xFFFFFFFF iterations" timeout 20 "$sharcbake" bake "$furnace" -o "$work/h.sharc" --resume "$work/huge.ckpt" $quick
says "$work/err.txt" "C8" "the message names rule C8"

# 8. A FIFO given as an input is refused instead of blocking.
mkfifo "$work/fifo_in"
expect 2 "info on a FIFO" timeout 20 "$sharcbake" info "$work/fifo_in"
expect 2 "render a FIFO scene" timeout 20 "$sharcbake" render "$work/fifo_in" -o "$work/f.exr" -q
expect 2 "resume from a FIFO" timeout 20 "$sharcbake" bake "$furnace" -o "$work/f.sharc" --resume "$work/fifo_in" $quick
expect 2 "render --cache FIFO" timeout 20 "$sharcbake" render "$furnace" -o "$work/f.exr" --cache "$work/fifo_in" --resolution 8 --spp 1 -q

# 12. A buffer URI that leaves the scene's folder is refused, and no byte of that file is echoed.
mkdir -p "$work/esc/inner"
printf 'SECRET-BYTES-0123' > "$work/esc/secret.bin"
printf '{ "asset": { "version": "2.0" }, "buffers": [ { "byteLength": 12, "uri": "../secret.bin" } ] }' > "$work/esc/inner/s.gltf"
expect 3 "a buffer outside the scene's folder" "$sharcbake" render "$work/esc/inner/s.gltf" -o "$work/e.exr" -q
says "$work/err.txt" "outside the scene's folder" "the message says why"
grep -q "SECRET" "$work/err.txt" "$work/out.txt" && fail "bytes of the outside file were echoed"
# A scene file that is not JSON: the parser's error does not quote the file's bytes.
printf 'root:x:0:0:SECRET-BYTES:/root:/bin/bash\n' > "$work/esc/notjson.gltf"
expect 3 "a scene that is not JSON" "$sharcbake" render "$work/esc/notjson.gltf" -o "$work/e.exr" -q
grep -q "SECRET\|root:x" "$work/err.txt" && fail "bytes of the file were echoed: $(cat "$work/err.txt")"

# 13. info escapes control characters of the metadata (a crafted value could drive the terminal).
python3 - "$work/a.sharc" "$work/esc.sharc" <<'PY' || fail "could not craft the cache"
import struct, sys, zlib
d = bytearray(open(sys.argv[1], 'rb').read())
count = struct.unpack_from('<I', d, 28)[0]
for i in range(count):
    e = 64 + 32 * i
    if d[e:e + 4] == b'META':
        offset, length = struct.unpack_from('<QQ', d, e + 8)
        at = d.index(b'stop_reason', offset) + len('stop_reason')   # the value follows its key
        d[at:at + 3] = b'\x1b[2'                                    # ESC [ 2: the start of "clear screen"
        struct.pack_into('<I', d, e + 24, zlib.crc32(d[offset:offset + length]))
struct.pack_into('<I', d, 60, zlib.crc32(d[64:64 + 32 * count], zlib.crc32(d[:60])))
open(sys.argv[2], 'wb').write(d)
PY
expect 0 "info on a cache whose metadata holds ESC" "$sharcbake" info "$work/esc.sharc"
says "$work/out.txt" 'stop_reason: \\x1B\[2' "ESC is printed as \\x1B"
tr -d '\n' < "$work/out.txt" | grep -q "$(printf '\033')" && fail "info printed a raw ESC"
expect 0 "info --json on it" "$sharcbake" info "$work/esc.sharc" --json
python3 -c "import json,sys; json.load(open(sys.argv[1]))" "$work/out.txt" || fail "info --json is not valid JSON"

# 5. A node chain 20,000 deep loads (no recursion); JSON nested 20,000 deep is refused before parsing.
# 6. A node scale that puts vertices near 1e19 is refused (exit 3), not an abort inside Embree.
mkdir -p "$work/deep"
cp "$scenes/furnace_rho090/furnace_rho090.bin" "$work/deep/"
python3 - "$scenes/furnace_rho090/furnace_rho090.gltf" "$work/deep" <<'PY' || fail "could not write the crafted scenes"
import copy, json, sys
base = json.load(open(sys.argv[1]))
chain = copy.deepcopy(base)
first = len(chain['nodes'])
n = 20000
for i in range(n):
    chain['nodes'].append({'children': [first + i + 1]} if i + 1 < n else {'mesh': 1})
chain['scenes'][0]['nodes'].append(first)
json.dump(chain, open(sys.argv[2] + '/chain.gltf', 'w'))
huge = copy.deepcopy(base)
huge['nodes'][1]['scale'] = [1e19, 1e19, 1e19]
json.dump(huge, open(sys.argv[2] + '/huge.gltf', 'w'))
nested = json.dumps(base)[:-1] + ', "extras": ' + '[' * 20000 + ']' * 20000 + '}'
open(sys.argv[2] + '/nested.gltf', 'w').write(nested)
PY
expect 0 "render a scene with a node chain 20,000 deep" "$sharcbake" render "$work/deep/chain.gltf" -o "$work/deep/chain.exr" --no-png --resolution 8 --spp 1 -q
expect 3 "JSON nested 20,000 deep" "$sharcbake" render "$work/deep/nested.gltf" -o "$work/deep/n.exr" --no-png --resolution 8 --spp 1 -q
says "$work/err.txt" "nested more than" "the message says the JSON is nested too deep"
expect 3 "vertices near 1e19" "$sharcbake" render "$work/deep/huge.gltf" -o "$work/deep/h.exr" --no-png --resolution 8 --spp 1 -q
says "$work/err.txt" "beyond" "the message says where the vertex lies"

# 9. Sizes are checked before allocating: an accessor of 2^26 elements without a bufferView, and
# a PNG declaring 16000x16000 texels, are refused at once (exit 3), saying so.
python3 - "$scenes/furnace_rho090/furnace_rho090.gltf" "$work/deep" <<'PY' || fail "could not write the crafted scenes"
import copy, json, struct, sys, zlib
base = json.load(open(sys.argv[1]))
big = copy.deepcopy(base)
big['accessors'].append({'componentType': 5126, 'count': 1 << 26, 'type': 'VEC3', 'min': [0, 0, 0], 'max': [0, 0, 0]})
big['meshes'][1]['primitives'][0]['attributes']['POSITION'] = len(big['accessors']) - 1
json.dump(big, open(sys.argv[2] + '/big_accessor.gltf', 'w'))
def chunk(kind, data):
    return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data))
png = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', 16000, 16000, 8, 0, 0, 0, 0)) + \
      chunk(b'IDAT', zlib.compress(b'\0' * 16001 * 4)) + chunk(b'IEND', b'')
open(sys.argv[2] + '/huge.png', 'wb').write(png)
textured = copy.deepcopy(base)
textured['images'] = [{'uri': 'huge.png'}]
textured['textures'] = [{'source': 0}]
textured['materials'][0].setdefault('pbrMetallicRoughness', {})['baseColorTexture'] = {'index': 0}
json.dump(textured, open(sys.argv[2] + '/huge_texture.gltf', 'w'))
PY
expect 3 "an accessor of 2^26 elements without a bufferView" "$sharcbake" render "$work/deep/big_accessor.gltf" -o "$work/deep/b.exr" --no-png --resolution 8 --spp 1 -q
says "$work/err.txt" "more than the scene's buffers can hold" "the message says why"
expect 3 "a 16000x16000 PNG" "$sharcbake" render "$work/deep/huge_texture.gltf" -o "$work/deep/t.exr" --no-png --resolution 8 --spp 1 -q
says "$work/err.txt" "max-texture-size" "the message names the option"
expect 3 "--max-texture-size 1 refuses the 2x2 texture" "$sharcbake" render "$work/tq/textured_quad.gltf" -o "$work/tq/t.exr" --no-png --max-texture-size 1 --resolution 8 --spp 1 -q
expect 0 "the default limit loads it" "$sharcbake" render "$work/tq/textured_quad.gltf" -o "$work/tq/t.exr" --no-png --resolution 8 --spp 1 -q

# 16. Two bakes sharing one --checkpoint: the second is refused at start (exit 2), the first goes on.
"$sharcbake" bake "$furnace" -o "$work/l1.sharc" --checkpoint "$work/l.ckpt" --iterations 1000000 --resolution 16x16 -q \
    >"$work/l1.out" 2>&1 &
first=$!
tries=0
while [ ! -e "$work/l.ckpt.lock" ] && [ $tries -lt 100 ]; do sleep 0.1; tries=$((tries + 1)); done
expect 2 "a second bake on the same checkpoint" "$sharcbake" bake "$furnace" -o "$work/l2.sharc" --checkpoint "$work/l.ckpt" $quick
says "$work/err.txt" "in use by another bake (process $first)" "the message names the other bake"
kill -TERM "$first"
wait "$first"
[ $? -eq 143 ] || fail "the first bake did not stop cleanly on SIGTERM"
[ -e "$work/l.ckpt.lock" ] && fail "the checkpoint lock was left behind"
expect 0 "the first bake's checkpoint resumes" "$sharcbake" bake "$furnace" -o "$work/l1.sharc" --resume "$work/l.ckpt" --iterations 4 --resolution 16x16 -q

# 16b. SIGTERM the moment the checkpoint is locked, while the scene loads and the bake is set up:
# the bake stops at its first iteration, releases the lock and leaves a checkpoint that resumes.
rm -f "$work/s.ckpt"
"$sharcbake" bake "$furnace" -o "$work/s.sharc" --checkpoint "$work/s.ckpt" --iterations 1000000 --resolution 16x16 -q \
    >"$work/s.out" 2>&1 &
early=$!
tries=0
while [ ! -e "$work/s.ckpt.lock" ] && [ $tries -lt 1000 ]; do sleep 0.01; tries=$((tries + 1)); done
kill -TERM "$early"
wait "$early"
[ $? -eq 143 ] || fail "SIGTERM during setup: the bake did not stop cleanly"
[ -e "$work/s.ckpt.lock" ] && fail "SIGTERM during setup: the checkpoint lock was left behind"
says "$work/s.out" "terminated (SIGTERM)" "SIGTERM during setup: the message says so"
expect 0 "SIGTERM during setup: the checkpoint resumes" "$sharcbake" bake "$furnace" -o "$work/s.sharc" --resume "$work/s.ckpt" --iterations 2 --resolution 16x16 -q

# 11. The occupancy view bounds the file's bucket size before scanning buckets per pixel.
python3 - "$work/a.sharc" "$work/bucket.sharc" <<'PY' || fail "could not craft the cache"
import struct, sys, zlib
d = bytearray(open(sys.argv[1], 'rb').read())
count = struct.unpack_from('<I', d, 28)[0]
for i in range(count):
    e = 64 + 32 * i
    if d[e:e + 4] == b'GRID':
        offset, length = struct.unpack_from('<QQ', d, e + 8)
        struct.pack_into('<I', d, offset + 12, 0xFFFFFFF0)                 # bucket_size
        struct.pack_into('<I', d, e + 24, zlib.crc32(d[offset:offset + length]))
struct.pack_into('<I', d, 60, zlib.crc32(d[64:64 + 32 * count], zlib.crc32(d[:60])))
open(sys.argv[2], 'wb').write(d)
PY
expect 3 "occupancy view of a cache with a bucket size of 2^32-16" timeout 20 "$sharcbake" render "$furnace" -o "$work/occ.exr" --no-png \
    --cache "$work/bucket.sharc" --debug-view occupancy --resolution 8 --spp 1 -q
says "$work/err.txt" "bucket size 4294967280" "the message names the bucket size"

# 14. A --capacity auto bake resumes with more iterations, on the table its first run chose.
expect 0 "an auto-capacity bake with a checkpoint" "$sharcbake" bake "$furnace" -o "$work/au.sharc" --capacity auto \
    --checkpoint "$work/au.ckpt" $quick
expect 0 "resumed with more iterations" "$sharcbake" bake "$furnace" -o "$work/au.sharc" --capacity auto \
    --resume "$work/au.ckpt" --iterations 6 --resolution 16x16 -q
expect 0 "info on the resumed cache" "$sharcbake" info "$work/au.sharc"
says "$work/out.txt" "iterations: 6" "the resumed auto bake ran to 6 iterations"

finish "hardening"
