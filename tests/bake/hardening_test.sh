#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Hostile inputs and outputs (issue 19, README "Untrusted scenes and caches"): an output never
# replaces a device, a FIFO or one of the command's inputs, a failed write keeps the previous
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
expect 2 "export-vdb -o /dev/full is refused" "$sharcbake" export-vdb "$work/a.sharc" -o /dev/full
mkfifo "$work/fifo_out"
expect 2 "render -o FIFO is refused" "$sharcbake" render "$furnace" -o "$work/fifo_out" --resolution 8 --spp 1 -q
[ -p "$work/fifo_out" ] || fail "the FIFO was replaced"
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
says "$work/err.txt" "write failed" "the message says the write failed"
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
expect 1 "render -o X.png (its own preview)" "$sharcbake" render "$furnace" -o "$work/x.png" --resolution 8 --spp 1 -q
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
