#!/usr/bin/env bash
# EXT_meshopt_compression as gltfpack (Debian's, the tool that writes it) writes it: shipped scenes
# packed with quantization only, with meshopt compression (-c, as .glb and as .gltf + .bin) and
# with compression and filters (-cc) render identically with sharcbake. The compression is
# lossless over the quantized data, so any difference is a decoding error.
set -euo pipefail
sharcbake=$1
scenes=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
status=0
render() {  # file -> image
    "$sharcbake" render "$1" -o "$2" --spp 8 --resolution 48x48 --seed 3 > "$work/log" 2>&1 ||
        { echo "FAIL: render of $1:"; cat "$work/log"; status=1; }
}
for scene in cornell_box textured_quad; do
    # Packed beside a copy of the scene: a packed .gltf refers to the original images by name.
    cp -r "$scenes/$scene" "$work/$scene"
    source=$work/$scene/$scene.gltf
    gltfpack -i "$source" -o "$work/$scene.q.glb" > /dev/null
    gltfpack -i "$source" -o "$work/$scene.c.glb" -c > /dev/null
    gltfpack -i "$source" -o "$work/$scene/$scene.c.gltf" -c > /dev/null
    gltfpack -i "$source" -o "$work/$scene.cc.glb" -cc > /dev/null
    grep -q EXT_meshopt_compression "$work/$scene.c.glb" || { echo "FAIL: gltfpack -c wrote no EXT_meshopt_compression"; status=1; }
    render "$work/$scene.q.glb" "$work/$scene.q.exr"
    for packed in c.glb $scene/$scene.c.gltf cc.glb; do
        [ "$packed" = "${packed%.gltf}" ] && packed_file=$work/$scene.$packed || packed_file=$work/$packed
        render "$packed_file" "$work/$scene.$(basename "$packed").exr"
        measures=$("$sharcbake" compare "$work/$scene.$(basename "$packed").exr" "$work/$scene.q.exr" 2>&1 || true)
        if grep -q "relative MSE 0," <<<"$measures"; then
            echo "ok: $scene packed as $(basename "$packed") renders as its quantized original"
        else
            echo "FAIL: $scene packed as $(basename "$packed") differs from its quantized original: $measures"
            status=1
        fi
    done
done
exit $status
