#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# A real bake exported with `sharcbake export-vdb`, checked by OpenVDB's own tools: vdb_print
# lists the grids, vdb_render renders the first float grid. Exit 77 (skipped) without the tools.
# Usage: vdb_tools_test.sh SHARCBAKE SCENES_DIR WORK_DIR
set -u
sharcbake=$1
scenes=$2
work=$3
for tool in vdb_print vdb_render; do
    if ! command -v "$tool" >/dev/null 2>&1; then
        echo "SKIP: $tool not found (Debian: apt-get install libopenvdb-tools)"; exit 77
    fi
done
rm -rf "$work" && mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }

"$sharcbake" bake "$scenes/cornell_box/cornell_box.gltf" -o "$work/cornell.sharc" --iterations 4 --resolution 64x64 -q \
    || fail "bake"
"$sharcbake" export-vdb --help >/dev/null || fail "export-vdb --help"
"$sharcbake" export-vdb "$work/cornell.sharc" -o "$work/cornell.vdb" || fail "export-vdb"
[ -s "$work/cornell.vdb" ] || fail "no .vdb written"

vdb_print "$work/cornell.vdb" >"$work/print.txt" 2>&1 || { cat "$work/print.txt"; fail "vdb_print"; }
cat "$work/print.txt"
first=$(vdb_print "$work/cornell.vdb" 2>/dev/null | awk '$2 == "float" {print $1; exit}')
[ "$first" = "density" ] || fail "first float grid listed is '$first', expected density"
for name in density color; do
    grep -q "^$name " "$work/print.txt" || fail "no grid '$name'"
done
grep -Eq '^level[0-9]+_radiance ' "$work/print.txt" || fail "no levelN_radiance grid"
grep -Eq '^level[0-9]+_samples ' "$work/print.txt" || fail "no levelN_samples grid"
vdb_print -l -m "$work/cornell.vdb" >"$work/meta.txt" 2>&1 || fail "vdb_print -l -m"
grep -q 'units' "$work/meta.txt" || fail "no units metadata"

# vdb_render renders the first float grid (density) from the scene's camera position.
vdb_render "$work/cornell.vdb" "$work/cornell.ppm" -res 64x64 -translate 0,0.5,2 -lookat 0,0.5,0 -cpus 2 \
    >"$work/render.txt" 2>&1 || { cat "$work/render.txt"; fail "vdb_render"; }
[ -s "$work/cornell.ppm" ] || fail "vdb_render wrote no image"

# Python: Debian's pyopenvdb (python3-openvdb, for Debian's own /usr/bin/python3) opens it.
/usr/bin/python3 - "$work/cornell.vdb" <<'PY' || fail "pyopenvdb could not read the export"
import sys
import pyopenvdb as vdb
names = [grid.name for grid in vdb.readAllGridMetadata(sys.argv[1])]
assert "density" in names and "color" in names, names
density = vdb.read(sys.argv[1], "density")
assert density.activeVoxelCount() > 0, "density grid is empty"
print("ok: pyopenvdb reads", len(names), "grids;", density.activeVoxelCount(), "active density voxels")
PY

# Bad input: a level the cache lacks is a usage error (1), a missing cache an I/O error (2).
"$sharcbake" export-vdb "$work/cornell.sharc" -o "$work/x.vdb" --levels 511 >/dev/null 2>&1
[ $? -eq 1 ] || fail "--levels 511 should exit 1"
"$sharcbake" export-vdb "$work/missing.sharc" -o "$work/x.vdb" >/dev/null 2>&1
[ $? -eq 2 ] || fail "missing cache should exit 2"
"$sharcbake" export-vdb "$work/cornell.sharc" -o "$work/x.vdb" --length-scale 0 >/dev/null 2>&1
[ $? -eq 1 ] || fail "--length-scale 0 should exit 1"

# --length-scale 1000: the same voxels in millimetres, and the file says so.
"$sharcbake" export-vdb "$work/cornell.sharc" -o "$work/mm.vdb" --levels 1 --length-scale 1000 >"$work/mm.txt" \
    || fail "export-vdb --length-scale 1000"
grep -q 'positions and sizes x 1000' "$work/mm.txt" || fail "export-vdb does not say the length scale"
vdb_print -l -m "$work/mm.vdb" >"$work/mm_meta.txt" 2>&1 || fail "vdb_print of the scaled export"
grep -q 'sharcbake_length_scale: 1000' "$work/mm_meta.txt" || fail "no sharcbake_length_scale metadata"
grep -q 'one VDB unit is 1/1000 glTF unit' "$work/mm_meta.txt" || fail "units metadata does not say the scale"
"$sharcbake" export-vdb "$work/cornell.sharc" -o "$work/m.vdb" --levels 1 -q || fail "export-vdb --levels 1"
vdb_print -l "$work/m.vdb" | awk '/voxel size/ {print $3; exit}' >"$work/m_size.txt"
vdb_print -l "$work/mm.vdb" | awk '/voxel size/ {print $3; exit}' >"$work/mm_size.txt"
awk -v m="$(cat "$work/m_size.txt")" -v mm="$(cat "$work/mm_size.txt")" \
    'BEGIN { r = mm / m; exit !(r > 999 && r < 1001) }' || fail "voxel size $(cat "$work/mm_size.txt") is not 1000x $(cat "$work/m_size.txt")"
echo "ok: export-vdb, vdb_print and vdb_render"
